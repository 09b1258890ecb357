#!/usr/bin/env bash
# karst calibrate on the real binary (issue 13, items 2, 3 and 6): usage errors (a --vary key that
# does not exist or holds no number, with a "did you mean"), the invariants of posterior.csv
# (priors respected, weights summing to 1, a tolerance that never increases), byte-identical
# outputs on 1 and 2 threads and under mpirun -np 2, a killed run continued to the same files,
# best.yaml that karst generate runs as is, and a report that renders.
# The scenario is tests/data/scenarios/calibrate/small.yaml (a few tens of ms per realisation);
# the "survey" is one of its own realisations.
set -u
KARST=$1
SRC=$2
fail=0
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
check() { # expected-exit description command...
  local want=$1 what=$2; shift 2
  "$@" >"$T/out" 2>&1; local got=$?
  if [ "$got" != "$want" ]; then echo "FAIL: $what: exit $got, expected $want"; cat "$T/out"; fail=1; else echo "ok: $what"; fi
}
says() { # text description: the last command's output contains text
  if grep -qF -- "$1" "$T/out"; then echo "ok: $2"; else echo "FAIL: $2: no \"$1\" in:"; cat "$T/out"; fail=1; fi
}
SCEN="$SRC/tests/data/scenarios/calibrate/small.yaml"
"$KARST" generate "$SCEN" -o "$T/truth" --seed 1001 --quiet || { echo "FAIL: generate the survey"; exit 1; }
SURVEY="$T/truth/network.vtp"

# --- usage errors: exit 2, a message naming the key, nothing created --------------------------
check 2 "calibrate without arguments" "$KARST" calibrate
check 2 "calibrate without --survey" "$KARST" calibrate "$SCEN" --vary tortuosity=0:1 -o "$T/u"
check 2 "calibrate without --vary" "$KARST" calibrate "$SCEN" --survey "$SURVEY" -o "$T/u"
check 2 "calibrate without -o" "$KARST" calibrate "$SCEN" --survey "$SURVEY" --vary tortuosity=0:1
bad_vary() { # spec expected-text
  check 2 "--vary $1 is a usage error" "$KARST" calibrate "$SCEN" --survey "$SURVEY" --vary "$1" -o "$T/u"
  says "$2" "--vary $1 says: $2"
  grep -qF -- "$1" "$T/out" || { echo "FAIL: --vary $1: the message does not name the parameter"; fail=1; }
}
bad_vary skeleton.gama=0.5:3 "unknown key 'gama' in skeleton (did you mean 'gamma'?)"
bad_vary amplifcation.steps=0:5 "did you mean 'amplification'?"
bad_vary name=0:1 "name is not a numeric key (it holds a string)"
bad_vary cost.fracture_combine=0:1 "cost.fracture_combine is not a numeric key"
bad_vary random.seed=0:9 "random.seed is not a numeric key"
bad_vary tortuosity.x=0:1 "not a map: there is no key tortuosity.x"
bad_vary fractures[4].weight=0:1 "fractures has 1 item"
bad_vary amplification.steps=0.5:3 "amplification.steps is an integer key"
bad_vary tortuosity=0:2 "tortuosity must be within [0, 1], got 2"
bad_vary skeleton.gamma=3:1 "LO must be below HI"
bad_vary skeleton.gamma=0:3:log "a log-uniform prior needs LO > 0"
bad_vary skeleton.gamma "needs KEY=LO:HI"
check 2 "--metrics with an unknown name" "$KARST" calibrate "$SCEN" --survey "$SURVEY" --vary tortuosity=0:1 --metrics aspl,cpdd -o "$T/u"
says "unknown metric 'cpdd' (did you mean 'cpd'?)" "--metrics suggests cpd"
for opt in "--particles 3" "--particles x" "--alpha 1" "--alpha 0" "--generations -1" "--min-acceptance 2" "-j 0"; do
  # shellcheck disable=SC2086
  check 2 "calibrate $opt" "$KARST" calibrate "$SCEN" --survey "$SURVEY" --vary tortuosity=0:1 $opt -o "$T/u"
done
[ ! -e "$T/u" ] && echo "ok: no usage error created the output directory" || { echo "FAIL: $T/u was created"; fail=1; }
check 1 "calibrate a missing scenario" "$KARST" calibrate /nonexistent.yaml --survey "$SURVEY" --vary tortuosity=0:1 -o "$T/u"
check 1 "calibrate against a missing survey" "$KARST" calibrate "$SCEN" --survey /nonexistent.3d --vary tortuosity=0:1 -o "$T/u"
"$KARST" help calibrate | grep -q -- "--allow-run-as-root" || { echo "FAIL: help calibrate"; fail=1; }

# --- a small calibration: an integer key and a log-uniform key --------------------------------
# 12 particles, 6 kept, 2 generations after the prior sample: 12 + 6 + 6 simulations.
ARGS=(calibrate "$SCEN" --survey "$SURVEY" --vary amplification.steps=0:4 --vary cost.fracture=0.05:20:log
  --vary tortuosity=0:1 --particles 12 --generations 2 --min-acceptance 0 --best-members 2 --seed 7 --quiet)
check 0 "calibrate -j 1" "$KARST" "${ARGS[@]}" -o "$T/a" -j 1
for f in posterior.csv generations.csv best.yaml report.html calibration.json calibration.key \
  generations/000/particles.csv generations/002/metrics.csv best/metrics.csv; do
  [ -s "$T/a/$f" ] || { echo "FAIL: missing $f"; fail=1; }
done
# posterior.csv: 3 generations x 6 particles; priors respected, integer values for the integer key,
# weights >= 0 summing to 1 in every generation, distances within that generation's tolerance,
# and the tolerance never increasing (strictly decreasing whenever a particle was accepted).
/usr/bin/python3 - "$T/a" <<'PY' || { echo "FAIL: posterior.csv invariants"; fail=1; }
import csv, math, sys
d = sys.argv[1]
rows = list(csv.DictReader(open(d + "/posterior.csv")))
gens = list(csv.DictReader(open(d + "/generations.csv")))
assert len(gens) == 3, gens
assert len(rows) == 18, len(rows)
tol = {int(g["generation"]): float(g["tolerance"]) for g in gens}
for g in range(3):
    part = [r for r in rows if int(r["generation"]) == g]
    assert len(part) == 6
    s = sum(float(r["weight"]) for r in part)
    assert abs(s - 1) < 1e-12, s
    for r in part:
        assert float(r["weight"]) >= 0
        k = float(r["amplification.steps"])
        assert k == int(k) and 0 <= k <= 4, k
        assert "." not in r["amplification.steps"]
        f = float(r["cost.fracture"])
        assert 0.05 <= f <= 20, f
        t = float(r["tortuosity"])
        assert 0 <= t <= 1, t
        assert float(r["distance"]) <= tol[g]
        assert int(r["simulated_in"]) <= g
for g in range(1, 3):
    assert tol[g] <= tol[g - 1], tol
    if int(gens[g]["accepted"]) > 0:
        assert tol[g] < tol[g - 1], (g, tol)
assert tol[2] < tol[0], tol
# every proposal of every generation inside the prior too
for g in range(3):
    for r in csv.DictReader(open(f"{d}/generations/{g:03d}/particles.csv")):
        assert 0 <= float(r["amplification.steps"]) <= 4 and 0.05 <= float(r["cost.fracture"]) <= 20
        assert 0 <= float(r["tortuosity"]) <= 1
print("posterior invariants hold; tolerances", [tol[g] for g in range(3)])
PY
# best.yaml: a complete scenario at the posterior medians that karst generate runs as is.
check 0 "karst validate DIR/best.yaml" "$KARST" validate "$T/a/best.yaml"
check 0 "karst generate DIR/best.yaml" "$KARST" generate "$T/a/best.yaml" -o "$T/bestgen" --quiet
/usr/bin/python3 - "$T/a" <<'PY' || { echo "FAIL: best.yaml holds the medians of calibration.json"; fail=1; }
import json, re, sys
d = sys.argv[1]
j = json.load(open(d + "/calibration.json"))
text = open(d + "/best.yaml").read()
body = "\n".join(l for l in text.splitlines() if not l.startswith("#"))
for p in j["parameters"]:
    key = p["key"].split(".")[-1]
    m = re.search(r"\b%s: ([^,}\s]+)" % re.escape(key), body)
    assert m, key
    assert float(m.group(1)) == p["median"], (key, m.group(1), p["median"])
    assert p["q05"] <= p["median"] <= p["q95"]
PY

# A scenario with a heightfield (hillside.yaml: terrain/hillside.asc, relative to the file):
# best.yaml in a directory elsewhere still finds the grid, from any working directory.
check 0 "calibrate hillside (4 particles, the prior sample only)" "$KARST" calibrate \
  "$SRC/datasets/scenarios/hillside.yaml" --survey "$SURVEY" --vary tortuosity=0:1 --particles 4 \
  --generations 0 --best-members 0 --quiet -o "$T/deep/er/hill"
grep -q 'heightfield: "\.\./' "$T/deep/er/hill/best.yaml" && echo "ok: the heightfield is rebased" ||
  { echo "FAIL: best.yaml heightfield"; grep heightfield "$T/deep/er/hill/best.yaml"; fail=1; }
(cd / && "$KARST" validate "$T/deep/er/hill/best.yaml" >"$T/out" 2>&1) &&
  echo "ok: karst validate DIR/best.yaml with a heightfield, from /" || { echo "FAIL: hillside best.yaml"; cat "$T/out"; fail=1; }

same_outputs() { # A B: the calibration's files byte for byte (timings lines, and the generations' ensemble.json, which name their own directory, and run logs ensemble_log.json left out)
  local d=0 f
  for f in posterior.csv generations.csv best.yaml report.html calibration.key best/metrics.csv; do
    cmp -s "$1/$f" "$2/$f" || { echo "differs: $f"; d=1; }
  done
  for f in $(cd "$1" && find generations best/realisations -type f ! -name ensemble.json ! -name ensemble_log.json | sort); do
    cmp -s "$1/$f" "$2/$f" || { echo "differs: $f"; d=1; }
  done
  diff <(grep -v '"timings"' "$1/calibration.json") <(grep -v '"timings"' "$2/calibration.json") >/dev/null || { echo "differs: calibration.json"; d=1; }
  return $d
}
no_leftovers() {
  local left; left=$(find "$1" -name '.*.tmp.*' -o -name '.*.lock')
  if [ -n "$left" ]; then echo "FAIL: left in $1: $left"; fail=1; fi
}
no_leftovers "$T/a"
check 0 "calibrate -j 2" "$KARST" "${ARGS[@]}" -o "$T/b" -j 2
same_outputs "$T/a" "$T/b" && echo "ok: -j 1 and -j 2 byte-identical" || { echo "FAIL: -j 1 vs -j 2"; fail=1; }
check 0 "calibrate again into a finished directory" "$KARST" "${ARGS[@]}" -o "$T/b" -j 2
same_outputs "$T/a" "$T/b" && echo "ok: a re-run changes nothing" || { echo "FAIL: re-run changed files"; fail=1; }
check 1 "another prior into the same directory" "$KARST" calibrate "$SCEN" --survey "$SURVEY" --vary tortuosity=0:0.5 --particles 12 --generations 2 --quiet -o "$T/b"
says "holds a calibration of another scenario, survey, seed" "a different calibration is refused"

# Kill mid-run (SIGTERM: handled, exit 1; SIGKILL: nothing handled), then run the same command:
# the same files as the uninterrupted run. The kill comes once 4 members of generation 0 exist,
# before the run can have finished (asserted: no posterior.csv).
members() { find "$1/generations" -mindepth 3 -maxdepth 3 -path '*/realisations/[0-9]*' -type d 2>/dev/null | wc -l; }
for sig in TERM KILL; do
  K="$T/k$sig"
  "$KARST" "${ARGS[@]}" -o "$K" -j 1 2>"$T/kill.err" &
  pid=$!
  for _ in $(seq 1 2400); do [ "$(members "$K")" -ge 4 ] && break; sleep 0.02; done
  kill -$sig $pid; wait $pid; rc=$?
  if [ -e "$K/posterior.csv" ]; then echo "FAIL: SIG$sig came too late (the run had finished)"; fail=1; fi
  if [ $sig = TERM ]; then
    [ $rc = 1 ] && grep -q "interrupted" "$T/kill.err" && echo "ok: SIGTERM: exit 1, says interrupted" ||
      { echo "FAIL: SIGTERM: exit $rc"; cat "$T/kill.err"; fail=1; }
  else
    [ $rc = 137 ] || { echo "FAIL: SIGKILL: exit $rc, expected 137"; fail=1; }
  fi
  check 0 "re-run after SIG$sig" "$KARST" "${ARGS[@]}" -o "$K" -j 2
  same_outputs "$T/a" "$K" && echo "ok: SIG$sig + re-run = uninterrupted" || { echo "FAIL: SIG$sig + re-run differs"; fail=1; }
  no_leftovers "$K"
done

# A larger --generations continues a finished calibration: generations 0-2 are unchanged.
check 0 "continue to 3 generations" "$KARST" "${ARGS[@]}" -o "$T/b" -j 2 --generations 3
if [ "$(grep -c '^3,' "$T/b/posterior.csv")" = 6 ] && diff <(grep -v '^3,' "$T/b/posterior.csv") "$T/a/posterior.csv" >/dev/null; then
  echo "ok: --generations 3 extends the run, generations 0-2 identical"
else
  echo "FAIL: extending the run"; fail=1
fi

# MPI with 2 processes writes the same files (see test_ensemble.sh for the LeakSanitizer note).
if ! command -v mpirun >/dev/null 2>&1; then
  echo "FAIL: mpirun not found (scripts/install-deps installs Open MPI)"; fail=1
elif mpirun --allow-run-as-root --oversubscribe -np 2 -x ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    "$KARST" "${ARGS[@]}" -o "$T/mpi" -j 1 >"$T/mpi.log" 2>&1; then
  same_outputs "$T/a" "$T/mpi" && echo "ok: mpirun -np 2 = single process" || { echo "FAIL: MPI output differs"; fail=1; }
  no_leftovers "$T/mpi"
elif grep -q "but this karst was built without MPI" "$T/mpi.log"; then
  echo "ok: a build without MPI refuses mpirun -np 2"
else
  echo "FAIL: mpirun"; cat "$T/mpi.log"; fail=1
fi

# The report renders without console errors, with every plot: 3 posterior histograms, the pair
# plot (with its 3 diagonal histograms nested), acceptance and tolerance, and one fit panel
# per metric (10).
if command -v chromium >/dev/null 2>&1; then
  bash "$SRC/tests/cli/test_report_chromium.sh" --check "$T/a/report.html" 19 || fail=1
else
  echo "FAIL: chromium not found (scripts/install-deps installs it)"; fail=1
fi
exit $fail
