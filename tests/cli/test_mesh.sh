#!/usr/bin/env bash
# karst mesh end to end: usage errors, a survey network (Monachou, shipped in datasets/) meshed to
# PLY and STL, the PLY checked closed and consistently oriented by an independent Python reading
# (every directed edge once, its reverse once), no partial file on failure.
set -u
KARST=$1
SRC=$2
DATA=$SRC/datasets/surveys/karstnet
PY=/usr/bin/python3
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

check 2 "no network" "$KARST" mesh -o "$TMP/a.ply"
check 2 "no output" "$KARST" mesh "$DATA/Monachou.pl"
check 2 "bad extension" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.obj"
check 2 "bad voxel" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --voxel -1
check 2 "bad box" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --box 1,2,3,0,5,6
check 2 "carve without scenario" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --carve
check 2 "unknown option" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --frob
check 2 "negative blend" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --blend -1
grep -q -- "--blend needs a width >= 0 in metres (0: hard union), got '-1'" "$TMP/err" && ok "blend message" || bad "blend message"
check 2 "blend not a number" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --blend wide
check 2 "bad realisation" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --realisation -3
check 0 "help" "$KARST" help mesh
check 1 "missing network" "$KARST" mesh /nonexistent/x.pl -o "$TMP/a.ply"
grep -q "/nonexistent/x.pl" "$TMP/err" && ok "missing file named" || bad "missing file not named"
[ ! -e "$TMP/a.ply" ] && ok "no output after failure" || bad "output left after failure"
check 1 "box thinner than two voxels" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/a.ply" --voxel 2 --box 0,0,0,3,3,3
[ ! -e "$TMP/a.ply" ] && ok "no output after failure" || bad "output left after failure"

# All outputs are checked before any work (the network is not even read: the message is about the
# directory, not about the missing network), written to temporaries and renamed together: a
# failure leaves neither the mesh nor a temporary.
check 1 "--sdf into a missing directory" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/c.ply" --sdf "$TMP/nodir/c.vti" --quiet
grep -q "c.vti: cannot write: directory '.*/nodir' does not exist" "$TMP/err" && ok "missing directory named" || { bad "missing directory not named"; cat "$TMP/err"; }
[ ! -e "$TMP/c.ply" ] && ok "no mesh left" || bad "mesh left although --sdf cannot be written"
check 1 "outputs checked before the input is read" "$KARST" mesh "$TMP/none.pl" -o "$TMP/c.ply" --sdf "$TMP/nodir/c.vti"
grep -q "nodir" "$TMP/err" && ! grep -q "none.pl" "$TMP/err" && ok "failed fast, on the output" || { bad "not checked first"; cat "$TMP/err"; }
mkdir "$TMP/dir.vtp"
check 1 "output is a directory" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/dir.vtp" --quiet
grep -q "dir.vtp: cannot write: it is a directory" "$TMP/err" && ok "directory named" || { bad "directory output message"; cat "$TMP/err"; }
rmdir "$TMP/dir.vtp"
ls -A "$TMP" | grep -q '\.tmp\.' && bad "temporary left: $(ls -A "$TMP")" || ok "no temporary left"

# The --sdf grid is checked before the polygonization. By hand: a 100 x 100 x 30 m box at 0.1 m
# is 1000 x 1000 x 300 cells, 1001² × 301 = 301602301 points > 2^28 = 268435456; the smallest
# two-digit voxel that fits is 0.11 m (911² × 274 = 227398354 points; 0.1039 m is the cube root).
check 1 "--sdf grid too large" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/g.ply" --sdf "$TMP/g.vti" --voxel 0.1 --box 0,0,0,100,100,30
grep -q -- "--sdf .*g.vti: the grid of 1000 x 1000 x 300 cells (301602301 points at --voxel 0.1) exceeds the limit of 268435456 points (2^28); use --voxel 0.11 or larger, or a smaller --box" "$TMP/err" \
  && ok "cells, limit and a larger voxel given" || { bad "--sdf size message"; cat "$TMP/err"; }
[ ! -s "$TMP/out" ] && [ ! -e "$TMP/g.ply" ] && [ ! -e "$TMP/g.vti" ] && ok "nothing written" || bad "output after the --sdf size error"

check 0 "mesh a survey to PLY" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/mon.ply" --voxel 0.5 --radius 0.8 -j 2 --quiet
check 0 "mesh a survey to STL" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/mon.stl" --voxel 0.5 --radius 0.8 -j 1 --quiet
"$PY" - "$TMP/mon.ply" "$TMP/mon.stl" <<'EOF' && ok "PLY closed and oriented, STL matches" || bad "PLY/STL content"
import struct, sys
data = open(sys.argv[1], 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
head = data[:end].decode().split('\n')
assert head[1] == 'format binary_little_endian 1.0', head[1]
nv = int([l for l in head if l.startswith('element vertex')][0].split()[2])
nf = int([l for l in head if l.startswith('element face')][0].split()[2])
assert 'property int tunnel_type' in head and 'property int feature' in head
assert len(data) == end + 24 * nv + 21 * nf, 'size'
edges = {}
off = end + 24 * nv
for (c, a, b, d, t, ft) in struct.iter_unpack('<Biiiii', data[off:off + 21 * nf]):
    assert c == 3 and 0 <= min(a, b, d) and max(a, b, d) < nv
    assert t == 0, 'survey edges are tubes (label 0), got %d' % t
    assert ft in (0, 1), 'feature is wall (0) or speleothem (1), got %d' % ft
    for e in ((a, b), (b, d), (d, a)):
        edges[e] = edges.get(e, 0) + 1
assert all(n == 1 for n in edges.values()), 'an edge used twice in one direction'
assert all((b, a) in edges for (a, b) in edges), 'an edge without its reverse'
stl = open(sys.argv[2], 'rb').read()
assert struct.unpack('<I', stl[80:84])[0] == nf and len(stl) == 84 + 50 * nf, 'stl size'
print('%d vertices, %d triangles' % (nv, nf))
EOF
# deterministic: the STL above was made with 1 thread, the PLY with 2; same triangle count is checked
# above, and two runs give the same bytes
check 0 "mesh again with 1 thread" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/mon1.ply" --voxel 0.5 --radius 0.8 -j 1 --quiet
cmp -s "$TMP/mon.ply" "$TMP/mon1.ply" && ok "same file with 1 and 2 threads" || bad "output depends on the thread count"

# The scenario's geometry section reaches karst mesh: a section with a hard union and no wall details
# gives the same bytes as --blend 0 --no-details (same box and seed); a bad value in it is refused
# with its file, line and column, before any output.
cat > "$TMP/geo.yaml" <<'EOF'
domain: {min: [-1000, -1000, -1000], max: [1000, 1000, 1000]}
terrain: {elevation: 999}
key_points:
  - {type: spring, position: [0, 0, 0]}
random: {seed: 5}
geometry:
  blend: 0
  details:
    tube: {amplitude: 0}
EOF
BOX=-25,-80,-25,30,10,15
check 0 "geometry section from the scenario" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/geo.ply" --voxel 0.5 --radius 0.8 --scenario "$TMP/geo.yaml" --box $BOX --quiet
check 0 "the same by options" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/opt.ply" --voxel 0.5 --radius 0.8 --blend 0 --no-details --seed 5 --box $BOX --quiet
check 0 "the default (blended, detailed) in that box" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/def.ply" --voxel 0.5 --radius 0.8 --seed 5 --box $BOX --quiet
cmp -s "$TMP/geo.ply" "$TMP/opt.ply" && ok "geometry section read (same bytes)" || bad "geometry section not applied"
cmp -s "$TMP/geo.ply" "$TMP/def.ply" && bad "hard union without details equals the default mesh" || ok "the default mesh is blended and detailed"
sed -i 's/  blend: 0/  blend: -2/' "$TMP/geo.yaml"
check 1 "bad geometry value" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/geo2.ply" --scenario "$TMP/geo.yaml" --quiet
grep -q "geo.yaml:7:10: geometry.blend must be auto or a width >= 0 m, got -2" "$TMP/err" && ok "bad geometry named by line and column" || { bad "geometry message"; cat "$TMP/err"; }
[ ! -e "$TMP/geo2.ply" ] && ok "no output after a bad geometry section" || bad "output left"

# Far from the origin (Monachou moved to UTM-like coordinates, easting +600 000 m, northing
# +5 123 000 m, where float32 steps are 6 cm and 0.5 m): the STL is written relative to an origin
# that is printed on stderr and stored in the header; header origin + float32 vertices give the
# PLY's float64 vertices (same network, same triangle order) to 1 mm, and no triangle collapses.
"$PY" - "$DATA/Monachou.pl" "$TMP/far.pl" <<'EOF'
import sys
out = []
for line in open(sys.argv[1]):
    f = line.split()
    if f and f[0] in ('VRTX', 'PVRTX'):
        f[2] = repr(float(f[2]) + 600000.0)
        f[3] = repr(float(f[3]) + 5123000.0)
        line = ' '.join(f) + '\n'
    out.append(line)
open(sys.argv[2], 'w').writelines(out)
EOF
check 0 "mesh a survey far from the origin to STL" "$KARST" mesh "$TMP/far.pl" -o "$TMP/far.stl" --voxel 0.5 --radius 0.8 --quiet
cp "$TMP/err" "$TMP/far.err"
check 0 "... and to PLY" "$KARST" mesh "$TMP/far.pl" -o "$TMP/far.ply" --voxel 0.5 --radius 0.8 --quiet
"$PY" - "$TMP/far.stl" "$TMP/far.ply" "$TMP/far.err" <<'EOF' && ok "STL origin printed and in the header; vertices to 1 mm, none collapsed" || bad "STL far from the origin"
import re, struct, sys
stl = open(sys.argv[1], 'rb').read()
m = re.match(rb'karst origin x=(-?\d+) y=(-?\d+) z=(-?\d+)', stl[:80])
assert m, stl[:80]
o = [float(v) for v in m.groups()]
err = open(sys.argv[3]).read()
assert 'origin x=%d y=%d z=%d' % tuple(o) in err, err
assert o[0] % 100 == 0 and o[1] % 100 == 0, o
assert 599800 <= o[0] <= 600000 and 5122800 <= o[1] <= 5123000 and o[2] == 0, o
ply = open(sys.argv[2], 'rb').read()
end = ply.index(b'end_header\n') + len(b'end_header\n')
head = ply[:end].decode().split('\n')
nv = int([l for l in head if l.startswith('element vertex')][0].split()[2])
nf = int([l for l in head if l.startswith('element face')][0].split()[2])
xyz = list(struct.iter_unpack('<3d', ply[end:end + 24 * nv]))
faces = list(struct.iter_unpack('<Biiiii', ply[end + 24 * nv:end + 24 * nv + 21 * nf]))
n = struct.unpack('<I', stl[80:84])[0]
assert n == nf > 1000, (n, nf)
worst = 0
for t in range(n):
    rec = struct.unpack('<12f', stl[84 + 50 * t:84 + 50 * t + 48])
    p = [[rec[3 + 3 * k + a] + o[a] for a in range(3)] for k in range(3)]
    for k in range(3):
        q = xyz[faces[t][1 + k]]
        worst = max(worst, max(abs(p[k][a] - q[a]) for a in range(3)))
    u = [p[1][a] - p[0][a] for a in range(3)]
    v = [p[2][a] - p[0][a] for a in range(3)]
    cr = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    assert cr != (0.0, 0.0, 0.0), 'triangle %d collapsed' % t
assert worst < 1e-3, worst
print('origin', o, 'worst vertex error %.2g m' % worst)
EOF

# VTK output read back by VTK itself: closed (no boundary or non-manifold edge by vtkFeatureEdges),
# the tunnel_type cell array present; the sampled field as image data with values of both signs.
check 0 "mesh to VTP with the field" "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/mon.vtp" --voxel 0.5 --radius 0.8 --sdf "$TMP/mon.vti" --quiet
"$PY" - "$TMP/mon.vtp" "$TMP/mon.vti" "$TMP/mon.ply" <<'EOF' && ok "VTP closed, labelled; VTI grid" || bad "VTP/VTI content"
import sys, vtk
r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1]); r.Update()
pd = r.GetOutput()
assert pd.GetNumberOfPolys() > 1000, pd.GetNumberOfPolys()
assert pd.GetCellData().GetArray('tunnel_type') is not None
feat = pd.GetCellData().GetArray('feature')
assert feat is not None and set(feat.GetValue(i) for i in range(feat.GetNumberOfTuples())) <= {0, 1}
fe = vtk.vtkFeatureEdges(); fe.SetInputData(pd)
fe.BoundaryEdgesOn(); fe.NonManifoldEdgesOn(); fe.FeatureEdgesOff(); fe.ManifoldEdgesOff(); fe.Update()
assert fe.GetOutput().GetNumberOfCells() == 0, fe.GetOutput().GetNumberOfCells()
head = open(sys.argv[3], 'rb').read(400).decode('latin-1')
nf = int([l for l in head.split('\n') if l.startswith('element face')][0].split()[2])
assert pd.GetNumberOfPolys() == nf, (pd.GetNumberOfPolys(), nf)
ri = vtk.vtkXMLImageDataReader(); ri.SetFileName(sys.argv[2]); ri.Update()
im = ri.GetOutput()
a = im.GetPointData().GetArray('sdf')
assert a is not None and a.GetNumberOfTuples() == im.GetNumberOfPoints() > 0
lo, hi = a.GetRange()
assert lo < 0 < hi, (lo, hi)
print(pd.GetNumberOfPolys(), 'triangles; image', im.GetDimensions())
EOF


# Writes that the file system refuses (a full disk; here ulimit -f with SIGXFSZ ignored, so
# write(2) fails with EFBIG): exit 1, a message naming the output and the reason, no file left.
# VTK 9.1's XML writer used to crash when its stream failed in the middle of a .vtp.
for ext in vtp ply stl; do
  rm -rf "$TMP/full" && mkdir "$TMP/full"
  ( trap '' XFSZ; ulimit -f 64; exec "$KARST" mesh "$DATA/Monachou.pl" -o "$TMP/full/cave.$ext" --voxel 0.5 --quiet ) 2>"$TMP/err"
  rc=$?
  if [ $rc -ne 1 ]; then bad "write failure .$ext: exit $rc, expected 1"; cat "$TMP/err"
  elif ! grep -q "writing $TMP/full/cave.$ext: .*File too large; no output was kept" "$TMP/err"; then bad "write failure .$ext: message"; cat "$TMP/err"
  elif [ -n "$(ls -A "$TMP/full")" ]; then bad "write failure .$ext left $(ls -A "$TMP/full")"
  else ok "write failure .$ext: exit 1, named, nothing left"; fi
done

exit $fail
