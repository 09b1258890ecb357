#!/usr/bin/env bash
# karst ensemble / compare / report on the real binary: exit codes 0 / 1 / 2, the compare
# statistics on a hand-made metrics table, and, once the generation pipeline is in the build,
# byte-identical ensembles for -j 1 and -j 2, kill + re-run, and MPI with 3 processes.
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

# --- usage errors -----------------------------------------------------------------------
check 2 "ensemble without arguments" "$KARST" ensemble
check 2 "ensemble without -o" "$KARST" ensemble x.yaml -n 3
# -n and -j out of range: exit 2, a message naming the option and the value, nothing created.
# The bounds are KARST_ENSEMBLE_MAX_MEMBERS = 100000000 and KARST_ENSEMBLE_MAX_THREADS = 1024.
bad_option() { # option value
  "$KARST" ensemble x.yaml -n 3 "$1" "$2" -o "$T/e" >"$T/out" 2>&1; local got=$?
  if [ "$got" != 2 ]; then echo "FAIL: ensemble $1 '$2': exit $got, expected 2"; cat "$T/out"; fail=1; return; fi
  grep -qF -- "$1 must be" "$T/out" && grep -qF -- "got '$2'" "$T/out" ||
    { echo "FAIL: ensemble $1 '$2': message does not name the option and value"; cat "$T/out"; fail=1; return; }
  [ ! -e "$T/e" ] || { echo "FAIL: ensemble $1 '$2' created $T/e"; fail=1; return; }
  echo "ok: ensemble $1 '$2' is a usage error"
}
for v in 0 -3 abc 1e8 " 5" "" 100000001 18446744073709551617; do bad_option -n "$v"; done
for v in 0 -1 x 2.5 1025 99999999999; do bad_option -j "$v"; done
check 2 "ensemble unknown option" "$KARST" ensemble x.yaml --frob -o "$T/e"
check 1 "ensemble missing scenario" "$KARST" ensemble /nonexistent.yaml -n 2 -o "$T/e"
check 2 "compare without directory" "$KARST" compare
check 2 "compare bad format" "$KARST" compare "$T" --format xml
check 1 "compare missing ensemble" "$KARST" compare /nonexistent/ens
check 2 "report without -o" "$KARST" report "$T"
check 1 "report missing ensemble" "$KARST" report /nonexistent/ens -o "$T/r.html"
[ ! -e "$T/r.html" ] || { echo "FAIL: report left a file after failing"; fail=1; }
"$KARST" help ensemble | grep -q -- "--allow-run-as-root" || { echo "FAIL: help ensemble"; fail=1; }

# --- compare on a hand-made ensemble: aspl = 1..10 --------------------------------------
mkdir -p "$T/hand"
{ echo "index,seed,aspl,cpd"; for i in $(seq 0 9); do echo "$i,$((i + 100)),$((i + 1)),"; done; } >"$T/hand/metrics.csv"
check 0 "compare, statistics only" "$KARST" compare "$T/hand" --format json --published "$SRC/datasets/published_metrics.csv"
# Hand values: mean 5.5, sd sqrt(82.5/9), type-7 p05 = 1.45, p95 = 9.55; cpd undefined (null);
# 34-cave ASPL range 2.321428571 - 55.72220194 (published_metrics.csv, Collon rows).
/usr/bin/python3 - "$T/out" <<'PY' || { echo "FAIL: compare json values"; fail=1; }
import json, math, sys
d = json.load(open(sys.argv[1]))
a = d[0]["metrics"]["aspl"]
assert d[0]["survey"] is None
assert a["n"] == 10 and abs(a["mean"] - 5.5) < 1e-12 and abs(a["sd"] - math.sqrt(82.5 / 9)) < 1e-12
assert abs(a["p05"] - 1.45) < 1e-12 and abs(a["p95"] - 9.55) < 1e-12
assert a["published_min"] == 2.321428571 and a["published_max"] == 55.72220194
assert d[0]["metrics"]["cpd"]["mean"] is None and d[0]["metrics"]["cpd"]["n"] == 0
PY
KARST_DATA_DIR="$SRC/datasets" "$KARST" compare "$T/hand" --format csv -o "$T/cmp.csv" || { echo "FAIL: compare -o"; fail=1; }
grep -q "^,aspl,,,10,5.5," "$T/cmp.csv" || { echo "FAIL: compare csv row"; cat "$T/cmp.csv"; fail=1; }

# --- the generation pipeline ----------------------------------------------------------------
SCEN="$SRC/datasets/scenarios/branchwork.yaml"
if ! "$KARST" ensemble "$SCEN" -n 4 -o "$T/a" -j 1 --seed 11 --quiet 2>"$T/err"; then
  echo "FAIL: karst ensemble"; cat "$T/err"; exit 1
fi
same_tree() { # A B: same files, same bytes (ensemble.json too); only the run log may differ
  local d=0
  diff <(cd "$1" && find . -type f | sort) <(cd "$2" && find . -type f | sort) || d=1
  for f in $(cd "$1" && find . -type f ! -name ensemble_log.json); do cmp -s "$1/$f" "$2/$f" || { echo "differs: $f"; d=1; }; done
  [ -f "$1/ensemble_log.json" ] || { echo "no ensemble_log.json in $1"; d=1; }
  grep -q wall_seconds "$1/ensemble.json" && { echo "ensemble.json holds the run log"; d=1; }
  return $d
}
no_leftovers() { # DIR: no hidden member temporaries and no lock file after a finished run
  local left; left=$(find "$1" -name '.*.tmp.*' -o -name '.ensemble.lock')
  if [ -n "$left" ]; then echo "FAIL: left in $1 after the run: $left"; fail=1; else echo "ok: nothing left over in $1"; fi
}
members() { ls "$1/realisations" 2>/dev/null | grep -c '^[0-9][0-9]*$'; }
no_leftovers "$T/a"
check 0 "ensemble -j 2" "$KARST" ensemble "$SCEN" -n 4 -o "$T/b" -j 2 --seed 11 --quiet
same_tree "$T/a" "$T/b" && echo "ok: -j 1 and -j 2 byte-identical" || { echo "FAIL: -j 1 vs -j 2"; fail=1; }
no_leftovers "$T/b"
[ "$(wc -l <"$T/a/metrics.csv")" = 5 ] || { echo "FAIL: metrics.csv rows"; fail=1; }
for f in ensemble.pvd ensemble.json realisations/0003/network.vtp realisations/0003/network_nodes.dat realisations/0003/network_links.dat; do
  [ -s "$T/a/$f" ] || { echo "FAIL: missing $f"; fail=1; }
done
# Member i is `karst generate --seed <its seed>`.
s1=$(sed -n 3p "$T/a/metrics.csv" | cut -d, -f2)
if "$KARST" generate "$SCEN" -o "$T/g" --seed "$s1" --quiet >"$T/gen.log" 2>&1; then
  cmp -s "$T/g/network.vtp" "$T/a/realisations/0001/network.vtp" && echo "ok: member 1 = karst generate --seed $s1" ||
    { echo "FAIL: member 1 differs from karst generate --seed $s1"; fail=1; }
else
  echo "FAIL: karst generate --seed $s1"; cat "$T/gen.log"; fail=1
fi

# One run at a time per DIR: flock(1) from util-linux holds DIR/.ensemble.lock (with a pid
# written in it, as karst writes its own) while a second karst ensemble starts on DIR. The
# second run must exit 1 naming the pid, and touch nothing: not the member temporary of the
# "running" ensemble, not the finished members, no new member.
mkdir "$T/a/realisations/.0004.tmp.999999"
echo 4242 >"$T/a/.ensemble.lock"
before=$(cd "$T/a" && find . -type f ! -name .ensemble.lock | sort | xargs md5sum)
flock -n -E 99 "$T/a/.ensemble.lock" "$KARST" ensemble "$SCEN" -n 5 -o "$T/a" -j 1 --seed 11 --quiet >"$T/out" 2>&1
rc=$?
if [ $rc != 1 ]; then echo "FAIL: second run on a locked DIR: exit $rc, expected 1"; cat "$T/out"; fail=1; fi
grep -qF "$T/a is in use by another karst ensemble (pid 4242" "$T/out" && echo "ok: locked DIR refused with the holder's pid" ||
  { echo "FAIL: locked DIR message"; cat "$T/out"; fail=1; }
[ -d "$T/a/realisations/.0004.tmp.999999" ] || { echo "FAIL: the refused run removed the other run's temporary"; fail=1; }
[ "$(cd "$T/a" && find . -type f ! -name .ensemble.lock | sort | xargs md5sum)" = "$before" ] &&
  echo "ok: the refused run changed no file" || { echo "FAIL: the refused run changed files in $T/a"; fail=1; }
[ "$(members "$T/a")" = 4 ] || { echo "FAIL: the refused run added members"; fail=1; }
rm -rf "$T/a/realisations/.0004.tmp.999999" "$T/a/.ensemble.lock"

# Kill mid-run, re-run, compare with an uninterrupted run: every file byte-identical (cmp),
# ensemble.json included; only the run log ensemble_log.json differs (its reused count is
# asserted below). SIGTERM is handled (members in progress remove their
# temporaries, exit 1); SIGKILL is not (temporaries and the lock file stay; the re-run removes
# them). The kill comes once 2 of 12 members are done, so the run cannot have finished: that is
# asserted (fewer than 12 members, no metrics.csv), not assumed.
check 0 "reference ensemble of 12" "$KARST" ensemble "$SCEN" -n 12 -o "$T/ref" -j 2 --seed 5 --quiet
no_leftovers "$T/ref"
for sig in TERM KILL; do
  K="$T/k$sig"
  "$KARST" ensemble "$SCEN" -n 12 -o "$K" -j 2 --seed 5 --quiet 2>"$T/kill.err" &
  pid=$!
  for _ in $(seq 1 1200); do [ "$(members "$K")" -ge 2 ] && break; sleep 0.05; done
  kill -$sig $pid; wait $pid; rc=$?
  kept=$(members "$K")
  if [ $sig = TERM ]; then
    [ $rc = 1 ] && grep -q "interrupted" "$T/kill.err" && echo "ok: SIGTERM: exit 1, says interrupted" ||
      { echo "FAIL: SIGTERM: exit $rc, expected 1 with 'interrupted'"; cat "$T/kill.err"; fail=1; }
    [ -z "$(find "$K" -name '.*.tmp.*')" ] && echo "ok: no temporary left after SIGTERM" ||
      { echo "FAIL: temporary files left after SIGTERM"; find "$K" -name '.*.tmp.*'; fail=1; }
  else
    [ $rc = 137 ] || { echo "FAIL: SIGKILL: exit $rc, expected 137"; fail=1; }
  fi
  if [ "$kept" -ge 2 ] && [ "$kept" -lt 12 ] && [ ! -e "$K/metrics.csv" ]; then
    echo "ok: SIG$sig stopped the run with $kept of 12 members"
  else
    echo "FAIL: SIG$sig: $kept members kept, metrics.csv $([ -e "$K/metrics.csv" ] && echo present || echo absent)"; fail=1
  fi
  check 0 "re-run after SIG$sig" "$KARST" ensemble "$SCEN" -n 12 -o "$K" -j 1 --seed 5 --quiet
  same_tree "$T/ref" "$K" && echo "ok: SIG$sig + re-run = uninterrupted" || { echo "FAIL: SIG$sig + re-run differs"; fail=1; }
  # the run log says what the re-run reused (the members kept) and computed (the rest)
  grep -q "\"reused\": $kept," "$K/ensemble_log.json" && grep -q "\"computed\": $((12 - kept))," "$K/ensemble_log.json" &&
    echo "ok: ensemble_log.json: $kept reused, $((12 - kept)) computed" ||
    { echo "FAIL: ensemble_log.json after SIG$sig: $(cat "$K/ensemble_log.json")"; fail=1; }
  no_leftovers "$K"
done
# MPI with 3 processes writes the same files. In sanitizer builds LeakSanitizer reports Open MPI's
# own allocations at exit (its plugins, ompi_op_base_op_select), not karst's: leak detection is
# off for this one run (karst's leaks are checked by every other run of this script).
if ! command -v mpirun >/dev/null 2>&1; then
  echo "FAIL: mpirun not found (scripts/install-deps installs Open MPI)"; fail=1
elif mpirun --allow-run-as-root --oversubscribe -np 3 -x ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    "$KARST" ensemble "$SCEN" -n 12 -o "$T/mpi" -j 1 --seed 5 --quiet >"$T/mpi.log" 2>&1; then
  same_tree "$T/ref" "$T/mpi" && echo "ok: mpirun -np 3 = single process" || { echo "FAIL: MPI output differs"; fail=1; }
  no_leftovers "$T/mpi"
elif grep -q "but this karst was built without MPI" "$T/mpi.log"; then
  # A build without MPI (-DKARST_WITH_MPI=OFF) must refuse, not let 3 processes race on DIR.
  [ ! -e "$T/mpi" ] && echo "ok: a build without MPI refuses mpirun -np 3 and creates nothing" ||
    { echo "FAIL: the refused MPI run created $T/mpi"; fail=1; }
else
  echo "FAIL: mpirun"; cat "$T/mpi.log"; fail=1
fi
# Under a launcher karst opens its MPI plugin, libkarst_mpi.so, from libkarst's own directory
# (libkarst itself is not linked with MPI). A libkarst without the plugin beside it must refuse
# cleanly, naming the plugin, and create nothing (a copy of the library in an empty directory).
LIBKARST=$(ldd "$KARST" | awk '/libkarst\.so/ { print $3; exit }')
if [ -e "$(dirname "$LIBKARST")/libkarst_mpi.so" ]; then
  mkdir -p "$T/lonely"
  cp "$(readlink -f "$LIBKARST")" "$T/lonely/$(basename "$LIBKARST")"
  if LD_LIBRARY_PATH="$T/lonely" OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 \
      "$KARST" ensemble "$SCEN" -n 2 -o "$T/noplugin" -j 1 --quiet >"$T/noplugin.log" 2>&1; then
    echo "FAIL: a launched run without the MPI plugin succeeded"; fail=1
  elif grep -q "MPI plugin (libkarst_mpi.so, next to libkarst) could not be loaded" "$T/noplugin.log" &&
      [ ! -e "$T/noplugin" ]; then
    echo "ok: without libkarst_mpi.so a launched run refuses and creates nothing"
  else
    echo "FAIL: missing MPI plugin: $(cat "$T/noplugin.log")"; fail=1
  fi
elif [ "$("$KARST" --version | awk '$1 == "MPI" { print $2 }')" = "Open" ]; then
  echo "FAIL: karst says it has MPI but $(dirname "$LIBKARST") holds no libkarst_mpi.so"; fail=1
fi
# Compare and report on the real ensemble with a real survey.
check 0 "compare with Sakany" "$KARST" compare "$T/ref" --survey "$SRC/datasets/surveys/karstnet/Sakany_nodes.dat"
check 0 "report" "$KARST" report "$T/ref" --survey "$SRC/datasets/surveys/karstnet/Sakany_nodes.dat" -o "$T/report.html"
# Every scenario parameter of ensemble.json is in the report, in full (Python's json and
# html.parser read both sides independently of karst).
/usr/bin/python3 "$SRC/tests/python/check_report_parameters.py" "$T/report.html" "$T/ref" ||
  { echo "FAIL: the report does not show every parameter of ensemble.json"; fail=1; }
exit $fail
