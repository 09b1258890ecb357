#!/usr/bin/env bash
# The four shipped presets against Table 2 of Paris et al. 2021: each is generated with its own
# seed (random.seed in the file, 2021) and measured with `karst metrics --observed`; every metric
# that Table 2 reports inside the range of the 34 caves of Collon et al. 2017 for the paper's
# network must be inside that range for ours too (branchwork and superimposed: all six; looping
# cave: mean length, orientation entropy, aspl, cpd; rectilinear maze: mean length, aspl, cpd — its
# mean degree and r_k are outside in the paper, and its orientation entropy is meant to be low).
# The rectilinear maze's orientation entropy must also be below 0.8 (the paper: 0.62), and every
# run must be connected (one component). This can fail: the metrics come from the real pipeline.
set -u
KARST=$1
SRC=$2
PY=/usr/bin/python3
export KARST_DATA_DIR=$SRC/datasets # --observed finds the published table there
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fail=1; }

ALL="mean_length orientation_entropy mean_degree correlation_vertex_degree aspl cpd"
check_preset() { # preset metrics-that-must-be-inside...
  local preset=$1; shift
  if ! "$KARST" generate "$SRC/datasets/scenarios/$preset.yaml" -o "$TMP/$preset" --quiet \
      2>"$TMP/err"; then
    bad "$preset: generate failed"; cat "$TMP/err"; return
  fi
  if ! "$KARST" metrics --format json --observed -q "$TMP/$preset/network.vtp" >"$TMP/$preset.json"; then
    bad "$preset: metrics failed"; return
  fi
  "$PY" - "$TMP/$preset.json" "$preset" "$@" <<'PY' && ok "$preset: Table 2 metrics in the observed range" || bad "$preset: Table 2 metrics"
import json, sys
r = json.load(open(sys.argv[1]))[0]
preset, keys = sys.argv[2], sys.argv[3:]
o = r["observed"]
out = [f"{k} = {r[k]:.4g} not in [{o[k]['min']:.4g}, {o[k]['max']:.4g}]" for k in keys if o[k]["outside"]]
print(preset + ": " + ", ".join(f"{k} = {r[k]:.4g}" for k in keys))
assert not out, out
assert r["components"] == 1, r["components"]
if preset == "rectilinear_maze":
    assert r["orientation_entropy"] < 0.8, r["orientation_entropy"]
PY
}

check_preset branchwork $ALL
check_preset superimposed $ALL
check_preset looping_cave mean_length orientation_entropy aspl cpd
check_preset rectilinear_maze mean_length aspl cpd
exit $fail
