#!/usr/bin/env bash
# sampling.points end to end on the real binary: the branchwork scenario on a given cloud (a
# 10 m lattice, so the counts are known by hand), what validate and run.json say about it, that
# a realisation is reproducible, that a run's own fill given back reproduces its network, and a
# malformed cloud refused with FILE:LINE:COLUMN, the key's place in the scenario, exit 1 and no
# output; and sampling.refine: [] on the cloud (the key points and the cloud alone).
set -u
KARST=$1
SRC=$(cd "$2" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fail=1; }
PY=/usr/bin/python3
# The points of a samples.vtp and the name of each one's source (Debian's VTK), for the checks below.
cat >"$tmp/samples_of.py" <<'EOF'
import vtk
def samples_of(path):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(path); r.Update()
    pd = r.GetOutput()
    a = pd.GetFieldData().GetAbstractArray("source_names")
    names = [a.GetValue(i) for i in range(a.GetNumberOfValues())]
    src = pd.GetPointData().GetArray("source")
    return [(pd.GetPoint(i), names[src.GetValue(i)]) for i in range(pd.GetNumberOfPoints())]
EOF
export PYTHONPATH="$tmp"

# The lattice x = 5, 15, ..., 395; y = 5, ..., 595; z = 5, ..., 95: 40 x 60 x 10 = 24 000 points,
# all inside the 400 x 600 x 100 m domain and below the terrain at 100 m.
{
  echo "# a 10 m lattice"
  echo "x,y,z"
  for z in $(seq 5 10 95); do
    for y in $(seq 5 10 595); do
      for x in $(seq 5 10 395); do echo "$x,$y,$z"; done
    done
  done
} >"$tmp/cloud.xyz"
[ "$(grep -c '^[0-9]' "$tmp/cloud.xyz")" = 24000 ] || bad "lattice has $(grep -c '^[0-9]' "$tmp/cloud.xyz") points"
sed 's/^sampling:$/sampling:\n  points: cloud.xyz/' "$SRC/datasets/scenarios/branchwork.yaml" >"$tmp/s.yaml"
grep -q "^  points: cloud.xyz" "$tmp/s.yaml" || bad "the scenario has no sampling.points"

"$KARST" validate "$tmp/s.yaml" >"$tmp/out" 2>&1 || bad "validate: exit $?"
grep -q "a cloud of 24000 points (sampling.points)" "$tmp/out" && ok "validate names the cloud" \
  || { bad "validate: $(cat "$tmp/out")"; }

for run in a b; do
  "$KARST" generate "$tmp/s.yaml" -o "$tmp/$run" --quiet --threads $([ $run = a ] && echo 1 || echo 2) \
    >"$tmp/gen.log" 2>&1 || { bad "generate $run: exit $?"; cat "$tmp/gen.log"; }
done
cmp -s "$tmp/a/network.vtp" "$tmp/b/network.vtp" && cmp -s "$tmp/a/network_links.dat" "$tmp/b/network_links.dat" \
  && ok "the same network on 1 and 2 threads" || bad "networks differ between 1 and 2 threads"
# run.json: the file, its count, and the points kept. Every lattice point is in the bedrock; those
# within min(feature_radius 6, fill_radius 10) = 6 m of a feature sample are dropped, so some but
# not all are kept, and every sample is a key point, a feature sample or a kept point.
$PY - "$tmp/a/run.json" <<'EOF' || fail=1
import json, sys
d = json.load(open(sys.argv[1]))
sp, c = d["parameters"]["sampling"], d["counts"]
errs = []
if not sp["points"].endswith("/cloud.xyz"): errs.append("points %r" % sp["points"])
if sp["points_count"] != 24000: errs.append("points_count %r" % sp["points_count"])
if not isinstance(sp["points_hash"], str) or len(sp["points_hash"]) != 16: errs.append("hash %r" % sp["points_hash"])
if not (0 < c["points_kept"] < 24000): errs.append("points_kept %r" % c["points_kept"])
if not (c["samples"] > c["points_kept"] + c["key_points"]): errs.append("samples %r" % c["samples"])
for e in errs: print("FAIL: run.json:", e)
if not errs: print("ok: run.json records the cloud (%d of 24000 points kept)" % c["points_kept"])
sys.exit(1 if errs else 0)
EOF

# sampling.refine: [] with the cloud: no layer is sampled finely, so the samples are the key points
# and the kept lattice points alone, and a point is dropped only within min(feature_radius 6,
# fill_radius 10) = 6 m of a key point. The expected count comes from the key points' positions
# in samples.vtp and the lattice, by brute force in Python (an independent computation).
sed 's/^  points: cloud.xyz$/  points: cloud.xyz\n  refine: []/' "$tmp/s.yaml" >"$tmp/bare.yaml"
"$KARST" validate "$tmp/bare.yaml" >"$tmp/out" 2>&1 && grep -q "sampling.refine \[\], " "$tmp/out" \
  && ok "validate names sampling.refine" || bad "validate with refine: $(cat "$tmp/out")"
# First the key points (samples.vtp of a run on the lattice), then a cloud of the lattice plus, for
# each key point k, k + (3, 0, 0), which the rule drops, and k - (0, 0, 7), which it keeps when no
# key point lies within 6 m and it is inside the domain (z > 0): that run is the one checked.
"$KARST" generate "$tmp/bare.yaml" -o "$tmp/bare0" --samples --quiet >"$tmp/gen.log" 2>&1 \
  || { bad "generate with refine: []: exit $?"; cat "$tmp/gen.log"; }
$PY - "$tmp/bare0/samples.vtp" "$tmp/cloud.xyz" "$tmp/cloud2.xyz" <<'EOF' || bad "writing the second cloud"
import sys
from samples_of import samples_of
keys = [p for p, s in samples_of(sys.argv[1]) if s == "key_point"]
with open(sys.argv[3], "w") as f:
    f.write(open(sys.argv[2]).read())
    for k in keys:
        f.write("%r %r %r\n%r %r %r\n" % (k[0] + 3, k[1], k[2], k[0], k[1], k[2] - 7))
EOF
sed 's#^  points: cloud.xyz$#  points: cloud2.xyz#' "$tmp/bare.yaml" >"$tmp/bare2.yaml"
"$KARST" generate "$tmp/bare2.yaml" -o "$tmp/bare" --samples --quiet >"$tmp/gen.log" 2>&1 \
  || { bad "generate with refine: [] on the second cloud: exit $?"; cat "$tmp/gen.log"; }
$PY - "$tmp/bare/run.json" "$tmp/bare/samples.vtp" <<'EOF' || fail=1
import json, sys
from samples_of import samples_of
d = json.load(open(sys.argv[1]))
c = d["counts"]
samples = samples_of(sys.argv[2])
keys = [p for p, s in samples if s == "key_point"]
kinds = sorted(set(s for p, s in samples))
far = lambda p: all((p[0] - k[0]) ** 2 + (p[1] - k[1]) ** 2 + (p[2] - k[2]) ** 2 >= 36 for k in keys)
lattice = sum(far((x, y, z)) for z in range(5, 100, 10) for y in range(5, 600, 10) for x in range(5, 400, 10))
below = sum(far((k[0], k[1], k[2] - 7)) and k[2] - 7 > 0 for k in keys)
expect = lattice + below
errs = []
if d["parameters"]["sampling"]["refine"] != []: errs.append("refine %r" % d["parameters"]["sampling"]["refine"])
if set(kinds) & {"horizon", "water_table", "permeability", "fill"} or "points" not in kinds: errs.append("sources %r" % kinds)
if d["parameters"]["sampling"]["points_count"] != 24000 + 2 * len(keys): errs.append("points_count")
if below == 0: errs.append("no point below a key point is kept: the check proves nothing")
if c["points_kept"] != expect: errs.append("points_kept %d, expected %d" % (c["points_kept"], expect))
if c["samples"] != c["key_points"] + expect: errs.append("samples %d" % c["samples"])
for e in errs: print("FAIL: refine: []:", e)
if not errs: print("ok: refine: [] runs on the %d key points and %d cloud points (%d of the lattice, %d of %d below a key point; none beside one), as counted" % (len(keys), expect, lattice, below, len(keys)))
sys.exit(1 if errs else 0)
EOF

# A run's own fill samples given back as the cloud reproduce its network: the same seed draws the
# same feature samples, every fill sample keeps r_m from them, and the samples are ordered
# within their source, so the graph and every later stage see the same points (an independent
# check: the expected network is the run without the cloud).
"$KARST" generate "$SRC/datasets/scenarios/branchwork.yaml" -o "$tmp/own" --samples --quiet \
  >"$tmp/gen.log" 2>&1 || { bad "generate with --samples: exit $?"; cat "$tmp/gen.log"; }
$PY - "$tmp/own/samples.vtp" "$tmp/own_fill.xyz" <<'EOF' || bad "extracting the fill from samples.vtp"
import sys
from samples_of import samples_of
with open(sys.argv[2], "w") as f:
    f.write("x y z\n")
    for p, s in samples_of(sys.argv[1]):
        if s == "fill":
            f.write("%r %r %r\n" % p)
EOF
sed "s#^sampling:\$#sampling:\n  points: $tmp/own_fill.xyz#" "$SRC/datasets/scenarios/branchwork.yaml" \
  >"$tmp/own.yaml"
"$KARST" generate "$tmp/own.yaml" -o "$tmp/again" --quiet >"$tmp/gen.log" 2>&1 \
  || { bad "generate on its own fill: exit $?"; cat "$tmp/gen.log"; }
n_fill=$(($(wc -l <"$tmp/own_fill.xyz") - 1))
kept=$($PY -c "import json,sys; print(json.load(open(sys.argv[1]))['counts']['points_kept'])" "$tmp/again/run.json")
if cmp -s "$tmp/own/network_nodes.dat" "$tmp/again/network_nodes.dat" \
  && cmp -s "$tmp/own/network_links.dat" "$tmp/again/network_links.dat" && [ "$kept" = "$n_fill" ] \
  && [ "$n_fill" -gt 1000 ]; then
  ok "the run's own fill as a cloud ($n_fill points, all kept) gives the same network"
else
  bad "own fill as a cloud: $kept of $n_fill kept, networks $(cmp "$tmp/own/network_links.dat" "$tmp/again/network_links.dat" 2>&1)"
fi

# A malformed cloud: the file's line and column, the key's place, exit 1, nothing written.
sed -i '7s/.*/5,15,abc/' "$tmp/cloud.xyz"
"$KARST" generate "$tmp/s.yaml" -o "$tmp/c" --quiet >"$tmp/out" 2>"$tmp/err"
got=$?
line=$(grep -n "^  points: cloud.xyz" "$tmp/s.yaml" | cut -d: -f1)
if [ $got = 1 ] && grep -qF "$tmp/cloud.xyz:7:6: field z: 'abc' is not a number (the points of sampling.points at $tmp/s.yaml:$line:11)" "$tmp/err" \
  && [ ! -e "$tmp/c" ]; then
  ok "a malformed cloud is refused at its line and column"
else
  bad "malformed cloud: exit $got: $(cat "$tmp/err")"
fi
exit $fail
