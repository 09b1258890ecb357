#!/usr/bin/env bash
# Reproducible experiment: the Collon et al. 2017 metrics of every shipped real survey, and the
# agreement with the published values where they exist (Sakany).
# Writes paper/tables/survey_metrics.md and paper/tables/sakany_agreement.md.
# Usage: analysis/survey_metrics.sh [KARST_BINARY]   (default build/karst)
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
out=paper/tables
mkdir -p "$out"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$KARST" metrics --format csv -o "$tmp/surveys.csv" \
  datasets/surveys/karstnet/Sakany_nodes.dat \
  datasets/surveys/karstnet/Monachou.pl \
  datasets/surveys/karstnet/g_huttes.sql \
  datasets/surveys/dowprov/DowProv.3d \
  datasets/surveys/tatra/processed/all_survex1.4.4.3d
/usr/bin/python3 analysis/tables.py surveys "$tmp/surveys.csv" > "$out/survey_metrics.md.tmp"
mv "$out/survey_metrics.md.tmp" "$out/survey_metrics.md"
/usr/bin/python3 analysis/tables.py agreement "$tmp/surveys.csv" datasets/published_metrics.csv Sakany \
  > "$out/sakany_agreement.md.tmp"
mv "$out/sakany_agreement.md.tmp" "$out/sakany_agreement.md"
echo "wrote $out/survey_metrics.md and $out/sakany_agreement.md"
