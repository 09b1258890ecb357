#!/usr/bin/env bash
# karst blocks and karst mesh --blocks end to end. Small inputs so that the test stays short
# under ASan (the paper's 20 m, 14 500-point tiles are measured by bench/bench_blocks): an 8 m tile
# from the CLI read back by python3-vtk9, the Table 1 statistics in run.json, byte-identical
# meshes on 1 and 2 threads; the shipped gorge scenario with 10 m tiles over a 20 m strip of it,
# with one user-authored block; a cave entrance carved out of the block-amplified terrain; usage
# errors.
set -euo pipefail
KARST=$1
SRC=$(cd "$2" && pwd)
PY=/usr/bin/python3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# One 8 m tile: the paper's density (about 14 500 points per 20 m cube, Table 1) gives
# 14 500 (8/20)³ = 928 points; the disc count stays the paper's 15 for this type.
tile=(blocks --tile equidimensional --tile-size 8 --seed 3 --voxel 0.25 --quiet)
"$KARST" "${tile[@]}" -o "$out/a" -j 1
"$KARST" "${tile[@]}" -o "$out/b" -j 2
[ -s "$out/a/tiles/equidimensional.vtp" ] || fail "no tiles/equidimensional.vtp"
cmp "$out/a/tiles/equidimensional.vtp" "$out/b/tiles/equidimensional.vtp" ||
  fail "1 and 2 threads differ"
"$PY" - "$out/a" <<'PY'
import json, sys
import vtk
from vtk.util.numpy_support import vtk_to_numpy as v2n
import numpy as np
d = sys.argv[1]
run = json.load(open(d + "/run.json"))
t = run["tiles"][0]
assert t["type"] == "equidimensional" and t["seed"] == 3, t
s = t["table1"]
assert 800 < s["points"] < 1050, s            # 928 at the paper's density
assert s["discs"] == 15, s                    # the paper's equidimensional count
assert 5 < s["blocks"] < s["points"], s
assert abs(s["mean_points_per_block"] * s["blocks"] - s["points"]) < 1e-6 * s["points"], s
assert "--tile-size 8" in run["command"], run["command"]
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + "/tiles/equidimensional.vtp"); r.Update()
pd = r.GetOutput()
assert pd.GetNumberOfPolys() > 10000, pd.GetNumberOfPolys()
ids = v2n(pd.GetCellData().GetArray("block_id"))
assert ids.min() >= 0 and ids.max() < s["blocks"], (ids.min(), ids.max())
# most blocks show at 0.25 m; slabs thinner than a voxel between close parallel fractures do not
assert len(np.unique(ids)) > 0.6 * s["blocks"], (len(np.unique(ids)), s["blocks"])
# every block closed: each undirected edge of a block's triangles is used exactly twice
T = v2n(pd.GetPolys().GetConnectivityArray()).reshape(-1, 3)
e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
_, uses = np.unique(e, axis=0, return_counts=True)
assert (uses == 2).all(), np.unique(uses)
PY

# The shipped gorge (Fig. 11 of the paper), made light: 10 m tiles (1 800 points each) over the
# strip 90 <= x <= 110 of its region, one authored block (a sphere of radius 1.5 m in the
# tabular tile) and one user-placed disc (the plane x = 2.5 of the tabular tile, radius 20 m: with
# its periodic copies it cuts the whole plane). Every other key as shipped.
G=$SRC/datasets/scenarios/gorge.yaml
sed -e "s|heightfield: terrain/gorge.asc|heightfield: $SRC/datasets/scenarios/terrain/gorge.asc|" \
  -e 's|tile_size: 20|tile_size: 10|' \
  -e 's|region: \[40, 20, 160, 100\]|region: [90, 20, 110, 100]|' "$G" > "$out/g.yaml"
cat >> "$out/g.yaml" <<'YAML'
  authored:
    - {tile: tabular, sphere: {center: [5, 5, 5], radius: 1.5}}
  user_discs:
    - {tile: tabular, center: [2.5, 5, 5], normal: [1, 0, 0], radius: 20}
YAML
[ "$(diff "$G" "$out/g.yaml" | grep -c '^>')" = 7 ] || fail "the gorge was not derived as meant"
"$KARST" validate "$out/g.yaml" > /dev/null
"$KARST" blocks "$out/g.yaml" -o "$out/g" --voxel 1 -j 2 --quiet
for f in tiles/equidimensional.vtp tiles/tabular.vtp terrain_blocks.vtp run.json; do
  [ -s "$out/g/$f" ] || fail "gorge: no $f"
done
"$PY" - "$out/g" <<'PY'
import json, sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy as v2n
d = sys.argv[1]
run = json.load(open(d + "/run.json"))
assert [t["type"] for t in run["tiles"]] == ["equidimensional", "tabular"], run["tiles"]
assert [t["authored_blocks"] for t in run["tiles"]] == [0, 1], run["tiles"]
assert [t["user_discs"] for t in run["tiles"]] == [0, 1], run["tiles"]
rep = run["replication"]
assert rep["copies"] > 0 and rep["block_triangles"] > 0, rep
assert [s["name"] for s in rep["strata"]] == ["lower", "upper"], rep["strata"]
def read(f):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(f); r.Update()
    return r.GetOutput()
# the authored sphere is the tabular tile's last block: its triangles lie on the sphere
tab = read(d + "/tiles/tabular.vtp")
ids = v2n(tab.GetCellData().GetArray("block_id"))
P = v2n(tab.GetPoints().GetData()); T = v2n(tab.GetPolys().GetConnectivityArray()).reshape(-1, 3)
last = run["tiles"][1]["table1"]["blocks"]
sph = np.unique(T[ids == last - 1])
assert len(sph) > 20, len(sph)
rad = np.linalg.norm(P[sph] - [5, 5, 5], axis=1)
assert abs(rad.mean() - 1.5) < 0.15 and rad.max() < 1.5 + 0.6, (rad.mean(), rad.max())
# no generated block enters the sphere: their vertices stay outside it (polygonized at 1 m)
other = np.unique(T[ids != last - 1])
assert np.linalg.norm(P[other] - [5, 5, 5], axis=1).min() > 1.5 - 0.6
# the user's disc: no block of the tabular tile straddles the plane x = 2.5 (nor its periodic
# copies at -7.5 and 12.5); each block's vertices lie on one side, within the 0.1 m tile voxel
for b in np.unique(ids):
    x = P[np.unique(T[ids == b]), 0]
    for plane in (-7.5, 2.5, 12.5):
        assert not (x.min() < plane - 0.2 and x.max() > plane + 0.2), (b, x.min(), x.max())
pd = read(d + "/terrain_blocks.vtp")
bid, bty = v2n(pd.GetCellData().GetArray("block_id")), v2n(pd.GetCellData().GetArray("block_type"))
P = v2n(pd.GetPoints().GetData()); T = v2n(pd.GetPolys().GetConnectivityArray()).reshape(-1, 3)
assert ((bty < 0) == (bid < 0)).all()
z = P[T].mean(axis=1)[:, 2]
# equidimensional (0) in the lower stratum (below 110 m), tabular (4) above: a block reaches at
# most one tile (10 m) across the boundary
assert (bty == 0).any() and (bty == 4).any(), np.unique(bty)
assert z[bty == 0].max() < 110 + 10 and z[bty == 4].min() > 110 - 10, (z[bty == 0].max(), z[bty == 4].min())
# no blocks on the flat plateau (140 m) or floor (80 m): block triangles between 70 and 150 m,
# and none on the flat parts far from the walls (the walls are 45 < y < 50 and 70 < y < 75)
zb, yb = z[bty >= 0], P[T].mean(axis=1)[bty >= 0, 1]
assert zb.min() > 70 and zb.max() < 150, (zb.min(), zb.max())
assert ((yb > 45 - 10) & (yb < 75 + 10)).all(), (yb.min(), yb.max())
PY
if "$KARST" blocks "$SRC/datasets/scenarios/hillside.yaml" -o "$out/h" 2> "$out/err"; then
  fail "a scenario without blocks accepted"
fi
grep -q "no blocks section" "$out/err" || fail "message: $(cat "$out/err")"

# karst mesh --carve --blocks: a conduit from inside the massif to the foot of the gorge's south
# wall (a Karstnet network written by hand), carved out of the bare and of the block-amplified
# terrain. With blocks: still one closed mesh with the conduit in it, and vertices standing out
# of the bare wall by more than half a metre (blocks), all of them on the south wall
# (45 < y < 50, between the floor at 80 m and the top of the box).
printf '100 30 82\n100 42 81\n100 54 81\n' > "$out/entrance_nodes.dat"
printf '1 2\n2 3\n' > "$out/entrance_links.dat"
mesh=(mesh "$out/entrance_nodes.dat" --carve --scenario "$out/g.yaml" --box 92,26,74,108,58,96
  --voxel 0.5 --radius 1.5 -j 2 --quiet)
"$KARST" "${mesh[@]}" -o "$out/bare.vtp"
"$KARST" "${mesh[@]}" --blocks -o "$out/blocks.vtp"
"$PY" - "$out/bare.vtp" "$out/blocks.vtp" <<'PY'
import sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy as v2n
def read(f):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(f); r.Update()
    return r.GetOutput()
bare, blk = read(sys.argv[1]), read(sys.argv[2])
for pd in (bare, blk):
    T = v2n(pd.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    e = np.sort(np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]]), axis=1)
    _, uses = np.unique(e, axis=0, return_counts=True)
    assert (uses == 2).all(), np.unique(uses)           # closed
    lab = v2n(pd.GetCellData().GetArray("tunnel_type"))
    assert (lab >= 0).sum() > 1000 and (lab < 0).sum() > 1000  # conduit walls and terrain
dist = vtk.vtkImplicitPolyDataDistance(); dist.SetInput(bare)
P = v2n(blk.GetPoints().GetData())
D = np.array([abs(dist.EvaluateFunction(p)) for p in P])
far = P[D > 0.5]
assert len(far) > 100, len(far)
assert far[:, 1].min() > 45 - 2 and far[:, 1].max() < 50 + 3, (far[:, 1].min(), far[:, 1].max())
assert far[:, 2].min() > 80 - 1, far[:, 2].min()
PY
if "$KARST" mesh "$out/entrance_nodes.dat" --blocks --scenario "$out/g.yaml" -o "$out/x.vtp" \
  2> "$out/err"; then fail "--blocks without --carve accepted"; fi
grep -q -- "--blocks needs --carve" "$out/err" || fail "message: $(cat "$out/err")"
[ ! -e "$out/x.vtp" ] || fail "output written for --blocks without --carve"

# usage errors: non-zero, a message, nothing written
if "$KARST" blocks --tile tabulr -o "$out/c" 2> "$out/err"; then fail "bad type accepted"; fi
grep -q "tabular" "$out/err" || fail "no list of types in: $(cat "$out/err")"
[ ! -e "$out/c" ] || fail "output written for a bad type"
if "$KARST" blocks --tile tabular --tile-size 2 -o "$out/c" 2> "$out/err"; then
  fail "a Poisson radius of 0.69 m in a 2 m tile accepted"
fi
grep -q "poisson_radius" "$out/err" || fail "message: $(cat "$out/err")"
[ ! -e "$out/c/run.json" ] || fail "run.json written for a bad tile"
if "$KARST" blocks "$G" --tile-size 8 -o "$out/e" 2> "$out/err"; then
  fail "--tile-size with a scenario accepted"
fi
if "$KARST" blocks -o "$out/d" 2> "$out/err"; then fail "no input accepted"; fi
if "$KARST" blocks --tile tabular 2> "$out/err"; then fail "no -o accepted"; fi
"$KARST" help blocks | grep -q "tiles/TYPE.vtp" || fail "help text"
echo "cli blocks: ok"
