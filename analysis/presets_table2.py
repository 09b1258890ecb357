"""Table 2 of Paris et al. 2021 for karst's four shipped presets (standard library only).

presets_table2.py METRICS.csv PUBLISHED.csv RUN_DIR
    METRICS.csv: `karst metrics --format csv` of RUN_DIR/<preset>_<seed>/network.vtp;
    PUBLISHED.csv: datasets/published_metrics.csv (the 34 caves of Collon et al. 2017, corrected
    2021), whose min and max per metric are the observed range; RUN_DIR/<preset>_<seed>/run.json
    gives the skeleton counts. Prints Markdown: our mean (min-max over the seeds) next to the
    paper's value, the observed range, and whether each mean is inside it.
"""
import csv
import json
import os
import sys
from collections import defaultdict

# The six metrics of Table 2: karst key, published_metrics.csv column, heading.
METRICS = [("mean_length", "mean_branch_len_m", "mean length (m)"),
           ("orientation_entropy", "H_orient", "H_O"),
           ("mean_degree", "mean_degree_k", "mean degree"),
           ("correlation_vertex_degree", "r_k_assortativity", "r_k"),
           ("aspl", "ASPL", "aspl"),
           ("cpd", "CPD", "cpd")]
# Paris et al. 2021, Table 2 (values as printed), and Table 1 (#S, skeleton length in km).
PAPER = {"branchwork": ["96", "0.9", "2.0", "-0.4", "4.1", "0.6"],
         "looping_cave": ["79", "0.9", "3.2", "0.04", "5.0", "0.2"],
         "rectilinear_maze": ["121", "0.6", "3.0", "0.0", "5.6", "0.1"],
         "superimposed": ["101", "0.8", "2.1", "-0.3", "4.9", "0.4"]}
TABLE1 = {"branchwork": (154, 2.3), "looping_cave": (668, 22.1),
          "rectilinear_maze": (830, 19.6), "superimposed": (209, 2.9)}
ORDER = ["branchwork", "looping_cave", "rectilinear_maze", "superimposed"]


def observed_ranges(path):
    rows = list(csv.DictReader(l for l in open(path) if not l.startswith("#")))
    # the 34 caves of Collon et al. 2017 (the other rows come from other studies), as
    # `karst metrics --observed` does
    rows = [r for r in rows if r.get("source", "").startswith("Collon")]
    out = {}
    for key, col, _ in METRICS:
        vals = [float(r[col]) for r in rows if r[col] not in ("", "NA")]
        out[key] = (min(vals), max(vals))
    return out, len(rows)


def main(metrics_csv, published, run_dir):
    obs, n_caves = observed_ranges(published)
    values = defaultdict(lambda: defaultdict(list))
    for r in csv.DictReader(open(metrics_csv)):
        run = os.path.basename(os.path.dirname(r["file"]))
        preset, seed = run.rsplit("_", 1)
        for key, _, _ in METRICS:
            values[preset][key].append(float(r[key]))
        counts = json.load(open(os.path.join(run_dir, run, "run.json")))["counts"]
        values[preset]["skeleton_nodes"].append(counts["skeleton_nodes"])
        values[preset]["skeleton_length"].append(counts["skeleton_length"] / 1000.0)
        values[preset]["seeds"].append(int(seed))
    print("| preset | row | " + " | ".join(h for _, _, h in METRICS) + " | #S | skeleton (km) |")
    print("|---" * (len(METRICS) + 4) + "|")
    for preset in ORDER:
        v = values[preset]
        if not v:
            continue
        n = len(v["seeds"])
        cells = []
        for key, _, _ in METRICS:
            xs = v[key]
            m = sum(xs) / n
            lo, hi = obs[key]
            mark = "" if lo <= m <= hi else " ✗"
            cells.append(f"{m:.3g} ({min(xs):.3g}–{max(xs):.3g}){mark}")
        s_mean = sum(v["skeleton_nodes"]) / n
        l_mean = sum(v["skeleton_length"]) / n
        print(f"| {preset} | karst, mean of {n} seeds (min–max) | " + " | ".join(cells) +
              f" | {s_mean:.0f} | {l_mean:.1f} |")
        paper = []
        for (key, _, _), x in zip(METRICS, PAPER[preset]):
            lo, hi = obs[key]
            # the paper prints rounded values: compare with the range rounded alike
            dec = len(x.split(".")[1]) if "." in x else 0
            inside = round(lo, dec) <= float(x) <= round(hi, dec)
            paper.append(x + ("" if inside else " ✗"))
        print(f"| {preset} | Paris et al. 2021 | " + " | ".join(paper) +
              f" | {TABLE1[preset][0]} | {TABLE1[preset][1]} |")
    print(f"| observed | {n_caves} caves, min–max | " +
          " | ".join(f"{obs[k][0]:.3g}–{obs[k][1]:.3g}" for k, _, _ in METRICS) + " | | |")
    print()
    print("✗: outside the observed range. Seeds: " +
          ", ".join(str(s) for s in sorted(set(values[ORDER[0]]["seeds"]))) +
          ". Observed range: datasets/published_metrics.csv (Collon et al. 2017, corrected 2021). "
          "#S: graph vertices on the skeleton before amplification; skeleton: its length.")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3])
