#!/usr/bin/env bash
# Reproducible table: the size of one realisation of each shipped scenario
# (datasets/scenarios/*.yaml) at its default seed (random.seed of the file), read from the
# run.json that `karst generate` writes: samples, the skeleton before amplification (length, #S
# vertices: Table 1 of Paris et al. 2021), the network after amplification (length, nodes,
# edges). Prints the Markdown table of docs/generation.md ("Presets").
# Usage: analysis/presets_counts.sh [KARST_BINARY]   (default build/karst)
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
runs=()
for scen in datasets/scenarios/*.yaml; do
  name=$(basename "$scen" .yaml)
  # massif.yaml is the regional-scale benchmark (10 M samples, bench/bench_massif), not a preset.
  [ "$name" = massif ] && continue
  "$KARST" generate "$scen" -o "$tmp/$name" --threads 1 --quiet
  runs+=("$tmp/$name/run.json")
done
/usr/bin/python3 - "${runs[@]}" <<'PY'
import json, os, sys
table1 = {"branchwork": "2.3 km, 154", "looping_cave": "22.1 km, 668",
          "rectilinear_maze": "19.6 km, 830", "superimposed": "2.9 km, 209"}
print("| preset | seed | reuse | samples | skeleton length | #S | Table 1 | network length | nodes | edges |")
print("|--------|------|-------|---------|-----------------|----|---------|----------------|-------|-------|")
for path in sys.argv[1:]:
    d = json.load(open(path))
    name = os.path.splitext(os.path.basename(d["scenario"]))[0]
    c, p = d["counts"], d["parameters"]
    print(f"| `{name}` | {d['seed']} | {p['reuse']:g} | {c['samples']} | "
          f"{c['skeleton_length'] / 1000:.1f} km | {c['skeleton_nodes']} | {table1.get(name, '–')} | "
          f"{c['total_length'] / 1000:.2f} km | {c['network_nodes']} | {c['network_edges']} |")
PY
