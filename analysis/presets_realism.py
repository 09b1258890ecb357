"""The ten metrics of Collon et al. 2017 for karst's shipped presets (standard library only).

presets_realism.py METRICS.csv PUBLISHED.csv
    METRICS.csv: `karst metrics --format csv` of <run>/<preset>_<seed>/network.vtp;
    PUBLISHED.csv: datasets/published_metrics.csv, whose rows from Collon et al. 2017 (corrected
    2021) give the observed range (min and max over the 34 caves) of each metric. Prints Markdown:
    per preset and metric, the members' mean, min-max and the share of members inside the range;
    then the real caves of each archetype (maze and looping caves named by Collon et al.) with
    the same metrics, so that a metric out of range can be read against caves of that type.
"""
import csv
import os
import statistics
import sys
from collections import defaultdict

# karst key, published_metrics.csv column, heading
METRICS = [("mean_length", "mean_branch_len_m", "mean length (m)"),
           ("cv_length", "CV_len", "cv length"),
           ("length_entropy", "H_len", "H_L"),
           ("tortuosity", "tortuosity", "tortuosity"),
           ("orientation_entropy", "H_orient", "H_O"),
           ("aspl", "ASPL", "aspl"),
           ("cpd", "CPD", "cpd"),
           ("mean_degree", "mean_degree_k", "mean degree"),
           ("cv_degree", "CV_degree", "cv degree"),
           ("correlation_vertex_degree", "r_k_assortativity", "r_k")]
ORDER = ["branchwork", "superimposed", "looping_cave", "rectilinear_maze"]
# Real caves of each archetype in the published table: the three 2-D network mazes digitised
# from Palmer (1991) maps, and the four 3-D caves with the highest mean degree (the most loops).
ARCHETYPE = {"rectilinear_maze": ["Crossroads", "Crevice", "BlueSpring"],
             "looping_cave": ["HanSurLesse", "Sakany", "Lechuguilla", "MammuthHoehle"]}


def fmt(x):
    return f"{x:.3g}" if abs(x) < 100 else f"{x:.0f}"


def main(metrics_csv, published):
    rows = [r for r in csv.DictReader(l for l in open(published) if not l.startswith("#"))
            if r.get("source", "").startswith("Collon")]
    rng = {}
    for key, col, _ in METRICS:
        vals = [float(r[col]) for r in rows if r[col] not in ("", "NA")]
        rng[key] = (min(vals), max(vals))
    values = defaultdict(lambda: defaultdict(list))
    seeds = defaultdict(set)
    for r in csv.DictReader(open(metrics_csv)):
        run = os.path.basename(os.path.dirname(r["file"]))
        preset, seed = run.rsplit("_", 1)
        seeds[preset].add(int(seed))
        for key, _, _ in METRICS:
            values[preset][key].append(float(r[key]))
    print("| metric | observed (34 caves) | " + " | ".join(ORDER) + " |")
    print("|---" * (len(ORDER) + 2) + "|")
    for key, _, head in METRICS:
        lo, hi = rng[key]
        cells = []
        for preset in ORDER:
            v = values[preset][key]
            inside = sum(lo <= x <= hi for x in v) / len(v)
            mark = "" if inside >= 0.9 else " ✗"
            cells.append(f"{fmt(statistics.mean(v))} ({fmt(min(v))}–{fmt(max(v))}), "
                         f"{100 * inside:.0f} % in{mark}")
        print(f"| {head} | {fmt(lo)}–{fmt(hi)} | " + " | ".join(cells) + " |")
    n = ", ".join(f"{p} {len(seeds[p])}" for p in ORDER)
    print()
    print(f"Each cell: mean over the members (min–max), and the share of members inside the "
          f"observed range; ✗: fewer than 90 % inside. Members: {n} (seeds "
          f"{min(min(s) for s in seeds.values())}–{max(max(s) for s in seeds.values())}). "
          f"Observed range: the {len(rows)} caves of Collon et al. 2017 (corrected 2021) in "
          f"datasets/published_metrics.csv.")
    print()
    print("| archetype | cave | " + " | ".join(h for _, _, h in METRICS) + " |")
    print("|---" * (len(METRICS) + 2) + "|")
    byname = {r["cave"]: r for r in rows}
    for preset, caves in ARCHETYPE.items():
        for cave in caves:
            r = byname[cave]
            cells = [fmt(float(r[c])) if r[c] not in ("", "NA") else "–" for _, c, _ in METRICS]
            print(f"| {preset} | {cave} | " + " | ".join(cells) + " |")
    print()
    print("Real caves of the two looping archetypes (Collon et al. 2017): the network mazes "
          "digitised from Palmer (1991) maps, and the 3-D caves of highest mean degree. –: not "
          "computed in the published table (2-D maps have no branch-length metrics).")


if __name__ == "__main__":
    main(*sys.argv[1:3])
