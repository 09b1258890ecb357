#!/usr/bin/env bash
# End-to-end test of `karst generate` (issue 3): usage errors, the files it
# writes, byte-identical outputs for the same seed whatever the thread count,
# a different network for another seed, and no output on failure.
# Usage: bash test_generate.sh KARST_BINARY SOURCE_DIR
set -u
KARST=$1
SRC=$2
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
PY=/usr/bin/python3
# The files are read back by VTK's own Python reader and run.json by Python's json module: a
# missing interpreter or module is a failure, not a skip (scripts/install-deps installs
# python3-vtk9, and CI has it).
"$PY" -c "import json, vtk" 2>/dev/null || fail "$PY with the vtk module is required (scripts/install-deps installs python3-vtk9)"

# Usage errors exit 2.
"$KARST" generate >/dev/null 2>&1; [ $? -eq 2 ] || fail "no arguments should exit 2"
"$KARST" generate x.yaml >/dev/null 2>&1; [ $? -eq 2 ] || fail "missing -o should exit 2"
"$KARST" generate x.yaml -o "$TMP/x" --bogus >/dev/null 2>&1; [ $? -eq 2 ] || fail "unknown option should exit 2"
"$KARST" generate x.yaml -o "$TMP/x" --seed -3 >/dev/null 2>&1; [ $? -eq 2 ] || fail "bad seed should exit 2"
"$KARST" generate --help | grep -q "run.json" || fail "help should describe run.json"

# A missing scenario is an error (exit 1) and leaves no output directory.
"$KARST" generate "$TMP/missing.yaml" -o "$TMP/none" 2>/dev/null; [ $? -eq 1 ] || fail "missing scenario should exit 1"
[ ! -e "$TMP/none" ] || fail "a failed run must not create its output directory"

# A small scenario (200 x 200 x 60 m, 5 key points) so the test runs in about a second.
cat > "$TMP/small.yaml" <<'EOF'
name: small
units: m
domain:
  min: [0, 0, 0]
  max: [200, 200, 60]
terrain:
  elevation: 60
water_table:
  elevation: 20
horizons:
  - {elevation: 35, dip: 0, dip_direction: 0, radius: 5}
fractures:
  - {dip_direction: 45, dip: 80, weight: 0.5}
permeability:
  background: 1
key_points:
  - {name: sinkA, type: sink, position: [20, 30, 58]}
  - {name: sinkB, type: sink, position: [170, 40, 58]}
  - {name: sinkC, type: sink, position: [60, 170, 58]}
  - {name: way1, type: waypoint, position: [100, 100, 35]}
  - {name: spring, type: spring, position: [195, 120, 20]}
sampling:
  fill_radius: 8
  feature_radius: 5
  k: 20
skeleton:
  gamma: 2.0
amplification:
  steps: 2
  points: 5
  dead_end_fraction: 0.6
tortuosity: 0.3
random:
  seed: 11
EOF

out=$("$KARST" generate "$TMP/small.yaml" -o "$TMP/a" --seed 5 --samples --threads 1 --quiet 2>&1)
status=$?
[ $status -eq 0 ] || fail "generate failed: $out"
for f in network.vtp network_nodes.dat network_links.dat samples.vtp geology.vtp network.paraview.py \
  run.json; do
  [ -s "$TMP/a/$f" ] || fail "$f missing or empty"
done
ls -A "$TMP/a" | grep -q '^\.' && fail "temporary files left behind: $(ls -A "$TMP/a")"
grep -q '"seed": 5,' "$TMP/a/run.json" || fail "run.json lacks the seed"
grep -q '"scenario_hash": "[0-9a-f]\{16\}"' "$TMP/a/run.json" || fail "run.json lacks the scenario hash"
grep -q '"gamma": 2' "$TMP/a/run.json" || fail "run.json lacks gamma"
grep -q '"skeleton":' "$TMP/a/run.json" || fail "run.json lacks the skeleton stage time"
# run.json: valid JSON; one time per real stage (the edge costs are computed with the graph, so
# there is no "cost" key); the radius field's parameters (the scenario's default correlation
# length, 100 m in docs/scenario.md, and the 256 waves of classification.c). network.vtp and
# samples.vtp read back by VTK with as many lines and points as run.json counts.
"$PY" - "$TMP/a" <<'EOF' || fail "run.json or the VTK files do not hold what they should"
import json, sys, vtk
d = json.load(open(sys.argv[1] + "/run.json"))
assert d["counts"]["network_edges"] > 0, d["counts"]
keys = list(d["stage_seconds"])
assert keys == ["sampling", "graph", "paths", "skeleton", "amplification", "classification"], keys
cl = d["parameters"]["classification"]
assert cl["radius_correlation"] == 100 and cl["radius_field_waves"] == 256, cl
assert d["parameters"]["terrain"] == {"elevation": 60}, d["parameters"]["terrain"]
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1] + "/network.vtp"); r.Update()
pd = r.GetOutput()
assert pd.GetNumberOfPoints() == d["counts"]["network_nodes"], pd.GetNumberOfPoints()
assert pd.GetNumberOfLines() == d["counts"]["network_edges"], pd.GetNumberOfLines()
for a in ("tunnel_type", "radius", "cost", "vadose", "zone", "spring", "branch_id",
          "amplification_step"):
    assert pd.GetCellData().GetArray(a) is not None, a
for a in ("kind", "water_table_distance", "spring"):
    assert pd.GetPointData().GetArray(a) is not None, a
zn = pd.GetFieldData().GetAbstractArray("zone_names")
assert [zn.GetValue(i) for i in range(zn.GetNumberOfValues())] == ["vadose", "epiphreatic", "phreatic"]
sn = pd.GetFieldData().GetAbstractArray("spring_names")
assert sn is not None and sn.GetNumberOfValues() >= 1
# geology.vtp: polygons with the feature arrays; the terrain (feature 0) is there.
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1] + "/geology.vtp"); r.Update()
g = r.GetOutput()
assert g.GetNumberOfPolys() > 0, g.GetNumberOfPolys()
feat = g.GetCellData().GetArray("feature")
assert feat is not None and g.GetCellData().GetArray("feature_id") is not None
assert 0 in {int(feat.GetValue(i)) for i in range(feat.GetNumberOfValues())}
fn = g.GetFieldData().GetAbstractArray("feature_names")
assert fn.GetValue(0) == "terrain" and fn.GetValue(6) == "exclusion", fn.GetValue(0)
# The flat terrain (z 60), horizon (35) and water table (20), none cut by the terrain, are each
# the domain's 200 x 200 m rectangle as two triangles: 40 000 m2 by hand.
import math
area, count = {}, {}
for c in range(g.GetNumberOfCells()):
    f = int(feat.GetValue(c))
    if f > 2: continue
    P = [g.GetPoints().GetPoint(g.GetCell(c).GetPointId(i)) for i in range(3)]
    u = [P[1][k] - P[0][k] for k in range(3)]; v = [P[2][k] - P[0][k] for k in range(3)]
    w = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    area[f] = area.get(f, 0) + 0.5 * math.sqrt(sum(x * x for x in w))
    count[f] = count.get(f, 0) + 1
    assert {p[2] for p in P} == {[60, 35, 20][f]}, (f, P)
assert count == {0: 2, 1: 2, 2: 2}, count
assert all(abs(area[f] - 40000) < 1e-6 for f in area), area
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1] + "/samples.vtp"); r.Update()
assert r.GetOutput().GetNumberOfPoints() == d["counts"]["samples"], r.GetOutput().GetNumberOfPoints()
EOF

# A heightfield terrain: run.json records its georeference as read. The grid below has
# xllcorner -10, yllcorner -5, cellsize 50, so (by hand) its cell centres start at
# xllcenter -10 + 25 = 15, yllcenter -5 + 25 = 20.
cat > "$TMP/hf.asc" <<'EOF'
ncols 6
nrows 6
xllcorner -10
yllcorner -5
cellsize 50
EOF
for i in 1 2 3 4 5 6; do echo "62 61 60 60 61 62" >> "$TMP/hf.asc"; done
sed 's|^  elevation: 60$|  heightfield: hf.asc|' "$TMP/small.yaml" > "$TMP/hf.yaml"
grep -q "heightfield: hf.asc" "$TMP/hf.yaml" || fail "could not write the heightfield scenario"
"$KARST" generate "$TMP/hf.yaml" -o "$TMP/h" --seed 5 --quiet || fail "heightfield run failed"
"$PY" - "$TMP/h/run.json" <<'EOF' || fail "run.json lacks the heightfield's georeference"
import json, sys
t = json.load(open(sys.argv[1]))["parameters"]["terrain"]
assert t["grid"].endswith("hf.asc") and len(t["grid_hash"]) == 16, t
assert (t["ncols"], t["nrows"], t["cellsize"]) == (6, 6, 50), t
assert (t["xllcorner"], t["yllcorner"], t["xllcenter"], t["yllcenter"]) == (-10, -5, 15, 20), t
EOF

# Same seed: byte-identical outputs, also with another thread count.
"$KARST" generate "$TMP/small.yaml" -o "$TMP/b" --seed 5 --samples --threads 2 --quiet || fail "second run failed"
for f in network.vtp network_nodes.dat network_links.dat samples.vtp geology.vtp network.paraview.py; do
  cmp -s "$TMP/a/$f" "$TMP/b/$f" || fail "$f differs between two runs with seed 5"
done

# FLANN's exact k-d tree (sampling.knn: flann) builds the same graph, hence the same network.
sed 's/^sampling:/sampling:\n  knn: flann/' "$TMP/small.yaml" > "$TMP/flann.yaml"
grep -q "knn: flann" "$TMP/flann.yaml" || fail "could not write the FLANN scenario"
"$KARST" generate "$TMP/flann.yaml" -o "$TMP/f" --seed 5 --quiet || fail "FLANN run failed"
grep -q '"knn": "flann"' "$TMP/f/run.json" || fail "run.json does not record knn: flann"
for f in network.vtp network_nodes.dat network_links.dat; do
  cmp -s "$TMP/a/$f" "$TMP/f/$f" || fail "$f differs between the grid and FLANN searches"
done

# Another seed: another network.
"$KARST" generate "$TMP/small.yaml" -o "$TMP/c" --seed 6 --quiet || fail "seed 6 run failed"
cmp -s "$TMP/a/network_nodes.dat" "$TMP/c/network_nodes.dat" && fail "seeds 5 and 6 gave the same network"
[ ! -e "$TMP/c/samples.vtp" ] || fail "samples.vtp written without --samples"

# The outputs are one set, committed together with run.json last. A run whose last file cannot be
# put in place (run.json is a non-empty directory, which rename cannot replace) fails with exit 1
# and leaves none of the set and no temporary file.
mkdir -p "$TMP/d/run.json/x"
"$KARST" generate "$TMP/small.yaml" -o "$TMP/d" --seed 5 --samples --quiet 2>"$TMP/d.err"
[ $? -eq 1 ] || fail "a run that cannot write run.json should exit 1"
grep -q "run.json: cannot rename into place" "$TMP/d.err" || fail "the error should name run.json: $(cat "$TMP/d.err")"
[ "$(ls -A "$TMP/d")" = "run.json" ] || fail "a failed run left part of its set: $(ls -A "$TMP/d")"
# Over a previous complete set (a copy of the seed-5 set in "$TMP/b", its run.json replaced by a
# directory only after the copy), the same failure puts back the previous files unchanged.
cp -r "$TMP/b" "$TMP/e"
"$KARST" generate "$TMP/small.yaml" -o "$TMP/e" --seed 6 --quiet 2>/dev/null || fail "seed 6 over seed 5 failed"
cmp -s "$TMP/c/network_nodes.dat" "$TMP/e/network_nodes.dat" || fail "a rerun did not replace the set"
[ ! -e "$TMP/e/samples.vtp" ] || fail "a rerun without --samples left the previous samples.vtp"
cp -r "$TMP/b" "$TMP/g"
rm "$TMP/g/run.json" && mkdir -p "$TMP/g/run.json/x"
"$KARST" generate "$TMP/small.yaml" -o "$TMP/g" --seed 6 --samples --quiet 2>/dev/null
[ $? -eq 1 ] || fail "a rerun that cannot write run.json should exit 1"
for f in network.vtp network_nodes.dat network_links.dat samples.vtp geology.vtp \
  network.paraview.py; do
  cmp -s "$TMP/b/$f" "$TMP/g/$f" || fail "$f of the previous set changed by a failed run"
done
[ "$(ls -A "$TMP/g" | wc -l)" -eq 7 ] || fail "a failed rerun left temporaries: $(ls -A "$TMP/g")"

# A file system that refuses the writes (a full disk; here the file-size limit of ulimit -f, with
# SIGXFSZ ignored so that write(2) fails with EFBIG instead): exit 1, a message naming the output
# and the system's reason, and nothing left in the directory. VTK 9.1's XML writer used to crash
# (a double delete) when its stream failed in the middle of network.vtp or samples.vtp; the
# limits below cut network.vtp (8 KiB) and samples.vtp (64 KiB) in the middle.
for lim in 8 64; do
  rm -rf "$TMP/full"
  ( trap '' XFSZ; ulimit -f $lim; exec "$KARST" generate "$TMP/small.yaml" -o "$TMP/full" --seed 5 --samples --quiet ) 2>"$TMP/full.err"
  rc=$?
  [ $rc -eq 1 ] || fail "a run whose writes fail (ulimit -f $lim) should exit 1, got $rc: $(cat "$TMP/full.err")"
  grep -q "writing $TMP/full/.*File too large; no output was kept" "$TMP/full.err" ||
    fail "the message should name the output and the reason: $(cat "$TMP/full.err")"
  [ -z "$(ls -A "$TMP/full" 2>/dev/null)" ] || fail "a run whose writes fail left files: $(ls -A "$TMP/full")"
done

echo "ok"
