#!/usr/bin/env bash
# karst metrics end to end on the shipped Karstnet data: formats, -o, --observed, --true-north,
# exit codes. Expected numbers: METRICS.md (Monachou, Karstnet 1.2.0) and published_metrics.csv.
set -u
KARST=$1
SRC=$2
DATA=$SRC/datasets/surveys/karstnet
PY=/usr/bin/python3
export KARST_DATA_DIR=$SRC/datasets # --observed finds the published table there
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fail=1; }
check() { # expected-exit description command...
  local want=$1 what=$2; shift 2
  "$@" >"$TMP/out" 2>"$TMP/err"; local got=$?
  if [ "$got" != "$want" ]; then bad "$what: exit $got, expected $want"; cat "$TMP/out" "$TMP/err"; else ok "$what"; fi
}

check 2 "no file" "$KARST" metrics
check 2 "bad format" "$KARST" metrics --format xml "$DATA/Monachou.pl"
check 2 "unknown option" "$KARST" metrics --frob "$DATA/Monachou.pl"
check 0 "help" "$KARST" help metrics
check 1 "missing file" "$KARST" metrics /nonexistent/x.pl
grep -q "/nonexistent/x.pl" "$TMP/err" && ok "missing file named" || bad "missing file not named"

# JSON: one object per file, every key of the issue, Monachou's values to 1e-9.
check 0 "json" "$KARST" metrics --format json "$DATA/Monachou.pl" "$DATA/Sakany_nodes.dat"
"$PY" - "$TMP/out" <<'EOF' && ok "json content" || bad "json content"
import json, sys
rows = json.load(open(sys.argv[1]))
assert len(rows) == 2, rows
keys = "file nodes edges mean_length cv_length length_entropy tortuosity orientation_entropy aspl cpd mean_degree cv_degree correlation_vertex_degree reduced_nodes reduced_edges components cycles howard_alpha howard_beta howard_gamma".split()
for r in rows:
    for k in keys:
        assert k in r, k
m = rows[0]
want = {"mean_length": 8.464115572807527, "cv_length": 0.9032881766753411,
        "length_entropy": 0.5510231430687663, "tortuosity": 1.2432160789955717,
        "orientation_entropy": 0.9837612087146957, "aspl": 7.5810126582278485,
        "cpd": 0.40396221841503066, "mean_degree": 2.175, "cv_degree": 0.500321411333914,
        "correlation_vertex_degree": -0.2497381415531946}
for k, v in want.items():
    assert abs(m[k] - v) <= 1e-9 * abs(v), (k, m[k], v)
assert (m["nodes"], m["edges"], m["reduced_nodes"], m["reduced_edges"], m["cycles"]) == (251, 258, 80, 87, 8)
s = rows[1]
assert (s["nodes"], s["edges"], s["reduced_nodes"], s["reduced_edges"], s["cycles"]) == (1716, 1784, 344, 412, 69)
assert abs(s["cpd"] - 0.267674075) < 5e-10 and abs(s["orientation_entropy"] - 0.9924004495) < 5e-11
EOF

# A single edge: undefined values are null in JSON and empty in CSV.
printf '0 0 0\n3 4 0\n' >"$TMP/one_nodes.dat"
printf '1 2\n' >"$TMP/one_links.dat"
check 0 "json single edge" "$KARST" metrics --format json "$TMP/one_nodes.dat"
"$PY" -c "import json,sys; r=json.load(open(sys.argv[1]))[0]; assert r['cv_length'] is None and r['howard_alpha'] is None and r['mean_length']==5.0, r" "$TMP/out" && ok "null for undefined" || bad "null for undefined"

# CSV: the same columns, one row per file; -o writes the file atomically.
check 0 "csv -o" "$KARST" metrics --format csv -o "$TMP/m.csv" "$DATA/Huttes_links.dat" "$DATA/Monachou.pl" "$TMP/one_links.dat"
[ ! -s "$TMP/out" ] && ok "-o leaves stdout empty" || bad "-o wrote to stdout"
"$PY" - "$TMP/m.csv" <<'EOF' && ok "csv content" || bad "csv content"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
assert len(rows) == 3
assert rows[0]["file"].endswith("Huttes_links.dat") and rows[0]["nodes"] == "41" and rows[0]["cycles"] == "1"
assert abs(float(rows[1]["aspl"]) - 7.5810126582278485) < 1e-12
assert rows[2]["cv_length"] == "" and rows[2]["mean_length"] == "5"
EOF
ls -a "$TMP" | grep -q '\.tmp\.' && bad "temporary file left" || ok "no temporary file left"

# --observed: ranges of the 34 published caves; Monachou is inside its own range, Huttes'
# 41 nodes are below the smallest published cave (145 stations).
check 0 "json --observed" "$KARST" metrics --format json --observed "$DATA/Monachou.pl" "$DATA/Huttes_nodes.dat"
"$PY" - "$TMP/out" <<'EOF' && ok "observed content" || bad "observed content"
import json, sys
mona, hut = json.load(open(sys.argv[1]))
o = mona["observed"]
assert o["mean_length"]["min"] == 8.464115573 and o["cycles"]["max"] == 779
assert not any(v["outside"] for v in o.values()), [k for k, v in o.items() if v["outside"]]
assert hut["observed"]["nodes"]["outside"] is True
EOF
check 0 "table --observed" "$KARST" metrics --observed "$DATA/Huttes_nodes.dat"
grep -q "outside" "$TMP/out" && grep -q "34 caves" "$TMP/out" && ok "table marks" || bad "table marks"
check 1 "--observed-table missing" "$KARST" metrics --observed-table /nonexistent.csv "$DATA/Monachou.pl"

# --true-north on a file without a coordinate system: reported, grid north kept.
check 0 "--true-north without CRS" "$KARST" metrics --format json --true-north "$DATA/Monachou.pl"
grep -q "no coordinate system" "$TMP/err" && ok "true-north reported" || bad "true-north not reported"
"$PY" -c "import json,sys; r=json.load(open(sys.argv[1]))[0]; assert r['true_north'] is False and abs(r['orientation_entropy']-0.9837612087146957)<1e-12" "$TMP/out" && ok "grid north kept" || bad "grid north kept"

# The .3d CS string is reported (DowProv: EPSG:7405, SOURCE.txt); --true-north rotates by the
# meridian convergence of the British National Grid at the survey (about -0.014 degrees).
check 0 "--true-north with a CRS" "$KARST" metrics --format json --true-north "$SRC/datasets/surveys/dowprov/DowProv.3d"
"$PY" -c "import json,sys; r=json.load(open(sys.argv[1]))[0]; assert r['crs']=='EPSG:7405' and r['true_north'] is True and -0.05<r['meridian_convergence']<0" "$TMP/out" && ok "CS string and convergence" || bad "CS string and convergence"
# A CS that cannot be converted offline (DowProv's header with EPSG:7405 changed to Poland's
# EPSG:2180, same length): one warning that names it once and says what is supported.
"$PY" -c "import sys; d=open(sys.argv[1],'rb').read(); open(sys.argv[2],'wb').write(d.replace(b'EPSG:7405', b'EPSG:2180', 1))" \
  "$SRC/datasets/surveys/dowprov/DowProv.3d" "$TMP/pl.3d"
check 0 "--true-north with an unconvertible CS" "$KARST" metrics --format json --true-north "$TMP/pl.3d"
[ "$(grep -o "EPSG:2180" "$TMP/err" | wc -l)" = 1 ] && grep -q "not convertible offline: only UTM" "$TMP/err" &&
  grep -q "^karst metrics: warning: $TMP/pl.3d: --true-north: coordinate system 'EPSG:2180' is not convertible offline: only UTM, the British National Grid, PROJ +proj=tmerc and latitude/longitude systems are supported; azimuths stay relative to grid north$" "$TMP/err" &&
  ok "unconvertible CS said once, with why" || { bad "unconvertible CS message"; cat "$TMP/err"; }
"$PY" -c "import json,sys; r=json.load(open(sys.argv[1]))[0]; assert r['crs']=='EPSG:2180' and r['true_north'] is False" "$TMP/out" && ok "grid north kept for EPSG:2180" || bad "grid north kept for EPSG:2180"
check 0 "table shows the CS" "$KARST" metrics "$SRC/datasets/surveys/dowprov/DowProv.3d"
grep -q "coordinate system: EPSG:7405" "$TMP/out" && ok "table CS line" || bad "table CS line"

# One bad file among good ones: the others are still measured, exit 1.
check 1 "mixed good and bad" "$KARST" metrics --format csv "$DATA/Monachou.pl" /nonexistent/y.pl
[ "$(wc -l <"$TMP/out")" = 2 ] && ok "good file still measured" || bad "good file not measured"
exit $fail
