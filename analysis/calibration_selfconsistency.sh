#!/usr/bin/env bash
# Reproducible experiment (issue 13, item 4a, the larger run): simulation-based calibration of
# `karst calibrate`. For each replicate r, true values of three parameters of
# tests/data/scenarios/calibrate/small.yaml are drawn from the prior (amplification.steps uniform
# on the integers 0-4, cost.fracture log-uniform 0.05-20, tortuosity uniform 0-1), a synthetic
# survey is generated with them, and the calibration must put the true values inside its 90 %
# credible intervals about 90 % of the time (Cook, Gelman & Rubin 2006; more for ABC with a
# tolerance above 0). Writes paper/tables/calibration_selfconsistency.md.
# Usage: analysis/calibration_selfconsistency.sh [KARST_BINARY]        (default build/karst)
# Environment: REPLICATES (10), PARTICLES (100), GENERATIONS (4), JOBS (all processors),
#   OUT (out/calibration_selfconsistency; kept, so a re-run continues).
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
REPLICATES=${REPLICATES:-10}
PARTICLES=${PARTICLES:-100}
GENERATIONS=${GENERATIONS:-4}
JOBS=${JOBS:-$(nproc)}
OUT=${OUT:-out/calibration_selfconsistency}
SCEN=tests/data/scenarios/calibrate/small.yaml
hash=$(sha1sum "$SCEN" | cut -c1-10)
OUT="$OUT/${hash}_n${PARTICLES}"
mkdir -p "$OUT" paper/tables
truths="$OUT/truths.csv"
# The true values of every replicate, drawn with Python's generator seeded by the replicate.
/usr/bin/python3 - "$SCEN" "$OUT" "$REPLICATES" <<'PY'
import math, random, re, sys
scen, out, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
text = open(scen).read()
rows = ["replicate,amplification.steps,cost.fracture,tortuosity"]
for r in range(1, n + 1):
    g = random.Random(r)
    steps = g.randrange(0, 5)
    frac = math.exp(g.uniform(math.log(0.05), math.log(20)))
    tort = g.uniform(0, 1)
    t = re.sub(r"steps: \d+", f"steps: {steps}", text)
    t = re.sub(r"fracture: [0-9.]+", f"fracture: {frac!r}", t)
    t = re.sub(r"(?m)^tortuosity: .*$", f"tortuosity: {tort!r}", t)
    assert t.count(f"steps: {steps}") == 1 and f"fracture: {frac!r}" in t
    open(f"{out}/truth_{r:03d}.yaml", "w").write(t)
    rows.append(f"{r},{steps},{frac!r},{tort!r}")
open(f"{out}/truths.csv", "w").write("\n".join(rows) + "\n")
PY
dirs=()
for r in $(seq 1 "$REPLICATES"); do
  id=$(printf %03d "$r")
  [ -s "$OUT/survey_$id/network.vtp" ] ||
    "$KARST" generate "$OUT/truth_$id.yaml" -o "$OUT/survey_$id" --seed $((5000 + r)) --quiet
  echo "== replicate $r of $REPLICATES"
  nice -n 10 "$KARST" calibrate "$SCEN" --survey "$OUT/survey_$id/network.vtp" \
    --vary amplification.steps=0:4 --vary cost.fracture=0.05:20:log --vary tortuosity=0:1 \
    --particles "$PARTICLES" --generations "$GENERATIONS" --min-acceptance 0 --best-members 0 \
    --seed "$r" -j "$JOBS" --quiet -o "$OUT/calibration_$id"
  dirs+=("$OUT/calibration_$id")
done
/usr/bin/python3 analysis/calibration_tables.py coverage "$truths" "${dirs[@]}" \
  >paper/tables/calibration_selfconsistency.md.tmp
mv paper/tables/calibration_selfconsistency.md.tmp paper/tables/calibration_selfconsistency.md
echo "wrote paper/tables/calibration_selfconsistency.md"
