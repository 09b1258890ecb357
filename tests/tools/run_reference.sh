#!/usr/bin/env bash
# ctest reference_metrics: the independent Python reference (karstnet_reference.py) on every
# shipped real survey, against `karst metrics --format json` to 1e-9 relative, and on Monachou
# and Sakany against Karstnet 1.2.0's values (METRICS.md) and the published table.
#   run_reference.sh KARST EXPORT SRC     (KARST = build/karst, EXPORT = build/tests/karst_export_network)
set -u
KARST=$1
EXPORT=$2
SRC=$3
PY=/usr/bin/python3
REF=$SRC/tests/tools/karstnet_reference.py
D=$SRC/datasets/surveys
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
pass=0
fail=0
run() { # description command...
  local what=$1; shift
  if "$@" >"$TMP/out" 2>&1; then
    echo "ok: $what ($(tail -n 1 "$TMP/out"))"; pass=$((pass + 1))
  else
    echo "FAIL: $what"; cat "$TMP/out"; fail=$((fail + 1))
  fi
}

# The script itself first, against values it must reproduce.
run "Monachou vs METRICS.md" sh -c "'$EXPORT' '$D/karstnet/Monachou.pl' '$TMP/mon' &&
  '$PY' '$REF' '$TMP/mon_nodes.dat' --expect monachou"
run "Sakany vs published table" "$PY" "$REF" "$D/karstnet/Sakany_nodes.dat" --expect sakany

# Then karst's metrics against the script on every shipped real survey.
for f in karstnet/Monachou.pl karstnet/Sakany_nodes.dat karstnet/Huttes_nodes.dat \
  karstnet/g_huttes.sql dowprov/DowProv.3d dowprov/DowProv.svx \
  dowprov/processed/DowProv_survex1.4.4.3d tatra/processed/all_survex1.4.4.3d tatra/all.svx; do
  run "$f" sh -c "'$EXPORT' '$D/$f' '$TMP/net' && '$KARST' metrics --format json '$D/$f' >'$TMP/k.json' &&
    '$PY' '$REF' '$TMP/net_nodes.dat' --compare '$TMP/k.json'"
done
echo "reference_metrics: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
