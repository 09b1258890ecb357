#!/usr/bin/env bash
# Debian 12's ParaView (5.11, in the chroot of scripts/paraview-chroot, which `make test`
# builds) runs the scripts karst writes beside real outputs: karst generate --samples, karst
# mesh --sdf, karst ensemble. pvbatch saves a screenshot and the lookup tables it built, and
# tests/python/check_paraview.py checks them against the data files read with VTK: the
# categories get their palette colours and their names from the files' *_names arrays, the
# legend shows them, the colour bars of continuous arrays carry their units. Then ParaView's
# GUI runs the network script the way `karst view` starts it (paraview --script, no __file__,
# in the script's directory) and must report no Python error.
#   bash test_paraview.sh KARST_BINARY SOURCE_DIR
# Fails (never skips) when the chroot is missing: CI builds it in `make test`.
set -u
KARST=$1
SRC=$2
CHROOT="$SRC/scripts/paraview-chroot"
if ! "$CHROOT" check; then
  echo "FAIL: no ParaView chroot at $("$CHROOT" path); build it with scripts/paraview-chroot"
  echo "      (make test does; about 6 minutes and 2.8 GB, once)"
  exit 1
fi
out=$(mktemp -d /tmp/karst-paraview.XXXXXX)
trap 'rm -rf "$out"' EXIT
fail=0
run() { echo "+ $*"; "$@" || { echo "FAIL: $*"; exit 1; }; }

run "$KARST" generate "$SRC/datasets/scenarios/branchwork.yaml" -o "$out/gen" --samples --seed 5 --quiet
mkdir -p "$out/mesh"
run "$KARST" mesh "$out/gen/network.vtp" -o "$out/mesh/cave.vtp" --voxel 2 --sdf "$out/mesh/cave.vti" --quiet
run "$KARST" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 2 -o "$out/ens" -j 2 --seed 3 --quiet
for f in gen/network.paraview.py gen/geology.vtp mesh/cave.paraview.py ens/ensemble.paraview.py \
  ens/realisations/0000/network.paraview.py; do
  [ -f "$out/$f" ] || { echo "FAIL: karst wrote no $f"; fail=1; }
done
[ $fail -eq 0 ] || exit 1

# X server: Xvfb started here, not by xvfb-run. xvfb-run waits for Xvfb's "ready" signal with
# a trap set before `wait`; on a loaded machine the signal can come first and xvfb-run then
# waits forever (seen: a run hung for 9 minutes). Xvfb -displayfd writes its display once it
# accepts connections (each run has its own /tmp and network namespace, so its own displays:
# scripts/paraview-chroot run). Every call runs under `timeout`, the init of the chroot's PID
# namespace (when it ends, Xvfb ends), so a hang fails the test instead of stalling CI.
# -noreset: pvbatch probes OpenGL on a first connection and reconnects; a server resetting
# after its last client refused the second one ("bad X server connection", seen at load 28).
XVFB_WAIT=60   # s for Xvfb to accept connections
PV_TIMEOUT=300 # s for one ParaView run (seconds on a quiet machine)
XRUN='cd "$1" && shift
df=$(mktemp /tmp/karst-xvfb.XXXXXX)
Xvfb -displayfd 3 -noreset -screen 0 1280x1024x24 -nolisten tcp 3>"$df" 2>"$df.log" &
xpid=$!
t=0
while [ ! -s "$df" ]; do
  if ! kill -0 $xpid 2>/dev/null || [ $t -ge $((XVFB_WAIT * 10)) ]; then
    echo "Xvfb failed to start:"; cat "$df.log"; rm -f "$df" "$df.log"; exit 97
  fi
  sleep 0.1; t=$((t + 1))
done
DISPLAY=":$(cat "$df")" "$@"
rc=$?
kill $xpid; wait $xpid 2>/dev/null
rm -f "$df" "$df.log"
exit $rc'
# An X server that could not be reached (an environment failure, not ParaView's) is retried,
# twice at most.
X_FAILURE="bad X server connection\|Xvfb failed to start\|cannot open display"
xrun() { # LOG DIR COMMAND [ARG]...: COMMAND run in DIR with an Xvfb display
  local log=$1 dir=$2 rc try
  shift 2
  for try in 1 2 3; do
    "$CHROOT" run --bind "$out" -- timeout -k 10 "$PV_TIMEOUT" /usr/bin/env \
      XVFB_WAIT="$XVFB_WAIT" /bin/sh -c "$XRUN" sh "$dir" "$@" >"$log" 2>&1
    rc=$?
    [ $rc -eq 124 ] && echo "timed out after $PV_TIMEOUT s" >>"$log"
    [ $rc -eq 0 ] || ! grep -q "$X_FAILURE" "$log" && return $rc
    echo "  (no X server: $(grep -m1 -o "$X_FAILURE" "$log")$(grep -m1 -o "DISPLAY=:[0-9]*" "$log"); again)"
  done
  return $rc
}
# pvbatch DIR SCRIPT NAME [ARGS]: screenshot $out/NAME.png and legend $out/NAME.json
pvbatch() {
  local dir=$1 script=$2 name=$3
  shift 3
  echo "+ pvbatch $dir/$script $*"
  if ! xrun "$out/$name.log" "$out/$dir" pvbatch "$script" --screenshot "$out/$name.png" \
      --legend "$out/$name.json" "$@"; then
    echo "FAIL: pvbatch $script"; cat "$out/$name.log"; exit 1
  fi
  if grep -q "Traceback\|Error" "$out/$name.log"; then
    echo "FAIL: pvbatch $script reported an error:"; cat "$out/$name.log"; exit 1
  fi
}
check() { # NAME SCRIPT DATA ARRAY [FLAGS]
  /usr/bin/python3 "$SRC/tests/python/check_paraview.py" "$out/$2" "$out/$1.json" "$out/$1.png" \
    "$out/$3" "$4" ${5:-} || fail=1
}

pvbatch gen network.paraview.py network
check network gen/network.paraview.py gen/network.vtp tunnel_type
pvbatch gen network.paraview.py samples --show samples
check samples gen/network.paraview.py gen/samples.vtp source
# The geology (hidden at start, translucent): its own "feature" categories, legend only.
pvbatch gen network.paraview.py geology --show geology
check geology gen/network.paraview.py gen/geology.vtp feature "--legend-only --role geology"
pvbatch mesh cave.paraview.py mesh-only --show mesh
check mesh-only mesh/cave.paraview.py mesh/cave.vtp tunnel_type --shaded
pvbatch mesh cave.paraview.py mesh
# The mesh script also shows the --sdf field: a slice with its titled, symmetric colour bar.
/usr/bin/python3 - "$out/mesh.json" <<'PY' || fail=1
import json, sys
sdf = json.load(open(sys.argv[1]))['arrays'].get('sdf')
assert sdf and sdf['bar_visible'], 'no visible colour bar for sdf'
assert '(m' in sdf['title'] and 'negative inside' in sdf['title'], sdf['title']
print('ok: sdf slice coloured, bar %r' % sdf['title'])
PY
pvbatch ens ensemble.paraview.py ensemble
check ensemble ens/ensemble.paraview.py ens/realisations/0000/network.vtp tunnel_type

# ParaView's GUI, as karst view starts it: in the script's directory, no __file__, no options.
echo "+ paraview --script=network.paraview.py --exit (GUI under Xvfb)"
if ! xrun "$out/gui.log" "$out/gen" paraview --script=network.paraview.py --exit; then
  echo "FAIL: ParaView's GUI did not run the script:"; cat "$out/gui.log"; fail=1
elif grep -q "Traceback\|Error\|is missing" "$out/gui.log"; then
  echo "FAIL: ParaView's GUI reported an error running the script:"; cat "$out/gui.log"; fail=1
else
  echo "ok: ParaView's GUI ran network.paraview.py without an error"
fi
[ $fail -eq 0 ] && echo "ok: ParaView shows karst's categories, names and units"
exit $fail
