#!/usr/bin/env bash
# karst blocks end to end: one tile per type from the CLI, read back by python3-vtk9, the
# Table 1 statistics in run.json, byte-identical meshes on 1 and 2 threads, usage errors.
set -euo pipefail
KARST=$1
SRC=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

"$KARST" blocks --tile tabular -o "$out/a" --seed 3 --voxel 0.25 -j 1 --quiet
"$KARST" blocks --tile tabular -o "$out/b" --seed 3 --voxel 0.25 -j 2 --quiet
[ -s "$out/a/tiles/tabular.vtp" ] || fail "no tiles/tabular.vtp"
cmp "$out/a/tiles/tabular.vtp" "$out/b/tiles/tabular.vtp" || fail "1 and 2 threads differ"
/usr/bin/python3 - "$out/a" <<'PY'
import json, sys
d = sys.argv[1]
run = json.load(open(d + "/run.json"))
t = run["tiles"][0]
assert t["type"] == "tabular" and t["seed"] == 3, t
s = t["table1"]
assert 12000 < s["points"] < 17000, s        # about 14 500 (Paris et al. 2020, Table 1)
assert s["discs"] == 30, s                    # the paper's tabular count
assert 20 < s["blocks"] < 400, s
assert abs(s["mean_points_per_block"] * s["blocks"] - s["points"]) < 1e-6 * s["points"], s
import vtk
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + "/tiles/tabular.vtp"); r.Update()
pd = r.GetOutput()
assert pd.GetNumberOfPolys() > 10000, pd.GetNumberOfPolys()
ids = pd.GetCellData().GetArray("block_id")
assert ids is not None
lo, hi = ids.GetRange()
assert lo == 0 and hi < s["blocks"], (lo, hi)
PY
# the scenario mode on the shipped gorge (coarse voxel to keep the test short)
"$KARST" blocks "$SRC/datasets/scenarios/gorge.yaml" -o "$out/g" --voxel 1 -j 2 --quiet
for f in tiles/equidimensional.vtp tiles/tabular.vtp terrain_blocks.vtp run.json; do
  [ -s "$out/g/$f" ] || fail "gorge: no $f"
done
/usr/bin/python3 - "$out/g" <<'PY'
import json, sys
d = sys.argv[1]
run = json.load(open(d + "/run.json"))
assert [t["type"] for t in run["tiles"]] == ["equidimensional", "tabular"], run["tiles"]
rep = run["replication"]
assert rep["copies"] > 0 and rep["block_triangles"] > 0, rep
assert [s["name"] for s in rep["strata"]] == ["lower", "upper"], rep["strata"]
import vtk
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + "/terrain_blocks.vtp"); r.Update()
pd = r.GetOutput()
bid, bty = pd.GetCellData().GetArray("block_id"), pd.GetCellData().GetArray("block_type")
assert bid is not None and bty is not None
n = pd.GetNumberOfPolys()
types = {}
for c in range(n):
    t = int(bty.GetValue(c))
    if t < 0:
        assert bid.GetValue(c) == -1
        continue
    cell = pd.GetCell(c)
    z = sum(pd.GetPoint(cell.GetPointId(k))[2] for k in range(3)) / 3
    types.setdefault(t, []).append(z)
# equidimensional (0) in the lower stratum (below 110 m), tabular (4) above: a block reaches at
# most one tile (20 m) across the boundary
assert 0 in types and 4 in types, types.keys()
assert max(types[0]) < 110 + 20 and min(types[4]) > 110 - 20, (max(types[0]), min(types[4]))
# no blocks on the flat plateau or floor: block triangles lie between 70 and 150 m
assert min(min(v) for v in types.values()) > 70 and max(max(v) for v in types.values()) < 150
PY
if "$KARST" blocks "$SRC/datasets/scenarios/hillside.yaml" -o "$out/h" 2> "$out/err"; then
  fail "a scenario without blocks accepted"
fi
grep -q "no blocks section" "$out/err" || fail "message: $(cat "$out/err")"

# usage errors: non-zero, a message, nothing written
if "$KARST" blocks --tile tabulr -o "$out/c" 2> "$out/err"; then fail "bad type accepted"; fi
grep -q "tabular" "$out/err" || fail "no list of types in: $(cat "$out/err")"
[ ! -e "$out/c" ] || fail "output written for a bad type"
if "$KARST" blocks -o "$out/d" 2> "$out/err"; then fail "no input accepted"; fi
if "$KARST" blocks --tile tabular 2> "$out/err"; then fail "no -o accepted"; fi
"$KARST" help blocks | grep -q "tiles/TYPE.vtp" || fail "help text"
echo "cli blocks: ok"
