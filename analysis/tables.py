"""Render the Markdown tables of paper/ from karst's CSV output (standard library only).

tables.py surveys METRICS.csv
    one row per file: counts and the ten metrics.
tables.py agreement METRICS.csv PUBLISHED.csv CAVE
    karst's value next to the published value of CAVE (Collon et al. 2017, corrected 2021)
    and the relative difference, for every metric the published table has.
"""
import csv
import os
import sys

METRICS = ["mean_length", "cv_length", "length_entropy", "tortuosity", "orientation_entropy",
           "aspl", "cpd", "mean_degree", "cv_degree", "correlation_vertex_degree"]
# published_metrics.csv column for each karst key
PUBLISHED = {"nodes": "n_stations", "edges": "s_shots", "mean_length": "mean_branch_len_m",
             "cv_length": "CV_len", "length_entropy": "H_len", "tortuosity": "tortuosity",
             "orientation_entropy": "H_orient", "aspl": "ASPL", "cpd": "CPD",
             "mean_degree": "mean_degree_k", "cv_degree": "CV_degree",
             "correlation_vertex_degree": "r_k_assortativity", "reduced_nodes": "N_reduced",
             "reduced_edges": "S_reduced", "components": "p_components", "cycles": "N_cycles"}


def fmt(v):
    if v in ("", None):
        return "–"
    x = float(v)
    return f"{int(x)}" if x == int(x) and abs(x) >= 1 and "." not in v else f"{x:.4g}"


def surveys(path):
    rows = list(csv.DictReader(open(path)))
    cols = ["nodes", "edges", "total_length"] + METRICS
    print("| survey | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for r in rows:
        name = os.path.basename(r["file"])
        print(f"| {name} | " + " | ".join(fmt(r[c]) for c in cols) + " |")


def agreement(path, published, cave):
    ours = next(r for r in csv.DictReader(open(path)) if cave.lower() in r["file"].lower())
    lines = [l for l in open(published) if not l.startswith("#")]
    pub = next(r for r in csv.DictReader(lines) if r["cave"] == cave)
    print(f"| metric ({cave}) | karst | published | relative difference |")
    print("|---|---|---|---|")
    for key, col in PUBLISHED.items():
        a, b = float(ours[key]), float(pub[col])
        rel = abs(a - b) / max(abs(a), abs(b)) if max(abs(a), abs(b)) > 0 else 0.0
        print(f"| {key} | {a:.10g} | {pub[col]} | {rel:.1e} |")


if __name__ == "__main__":
    if sys.argv[1] == "surveys":
        surveys(sys.argv[2])
    elif sys.argv[1] == "agreement":
        agreement(sys.argv[2], sys.argv[3], sys.argv[4])
    else:
        sys.exit(f"unknown table {sys.argv[1]}")
