#!/usr/bin/env bash
# Reproducible experiment: Table 2 of Paris et al. 2021 for karst's four shipped presets
# (datasets/scenarios/{branchwork,looping_cave,rectilinear_maze,superimposed}.yaml): each is
# generated with several seeds by the real binary, measured with `karst metrics`, and the mean
# of the six Table 2 metrics is put next to the paper's value and the range observed over the 34
# caves of Collon et al. 2017. Writes paper/tables/presets_table2.md.
# Usage: analysis/presets_table2.sh [KARST_BINARY] [SEEDS...]   (default build/karst, seeds 1-5)
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
shift || true
SEEDS=${*:-1 2 3 4 5}
out=paper/tables
mkdir -p "$out"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
files=()
for preset in branchwork looping_cave rectilinear_maze superimposed; do
  for seed in $SEEDS; do
    "$KARST" generate "datasets/scenarios/$preset.yaml" -o "$tmp/${preset}_$seed" --seed "$seed" --quiet
    files+=("$tmp/${preset}_$seed/network.vtp")
  done
done
"$KARST" metrics --format csv -o "$tmp/presets.csv" -q "${files[@]}"
/usr/bin/python3 analysis/presets_table2.py "$tmp/presets.csv" datasets/published_metrics.csv "$tmp" \
  > "$out/presets_table2.md.tmp"
mv "$out/presets_table2.md.tmp" "$out/presets_table2.md"
echo "wrote $out/presets_table2.md"
