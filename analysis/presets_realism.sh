#!/usr/bin/env bash
# Reproducible experiment (issue 13, item 1): are the shipped presets inside the range of the 34
# real caves of Collon et al. 2017 in all ten of its metrics? Each of the four presets
# (datasets/scenarios/{branchwork,looping_cave,rectilinear_maze,superimposed}.yaml) is generated
# with seeds 1-20 by the real binary and measured with `karst metrics`; for each metric the table
# gives the members' mean, their min-max and the share of members inside the observed range, and
# the real caves of the preset's archetype. Writes paper/tables/presets_realism.md.
# Usage: analysis/presets_realism.sh [KARST_BINARY] [SEEDS...]   (default build/karst, seeds 1-20)
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
shift || true
SEEDS=${*:-$(seq 1 20)}
out=paper/tables
mkdir -p "$out"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
files=()
for preset in branchwork superimposed looping_cave rectilinear_maze; do
  for seed in $SEEDS; do
    "$KARST" generate "datasets/scenarios/$preset.yaml" -o "$tmp/${preset}_$seed" --seed "$seed" --quiet
    files+=("$tmp/${preset}_$seed/network.vtp")
  done
done
"$KARST" metrics --format csv -o "$tmp/presets.csv" -q "${files[@]}"
/usr/bin/python3 analysis/presets_realism.py "$tmp/presets.csv" datasets/published_metrics.csv \
  > "$out/presets_realism.md.tmp"
mv "$out/presets_realism.md.tmp" "$out/presets_realism.md"
echo "wrote $out/presets_realism.md"
