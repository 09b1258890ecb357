#!/usr/bin/python3
"""Check a conditioned network against Survex's own reduction of the survey (tests/cli/
test_conditioning.sh). Independent of karst's readers: the survey comes from `dump3d` on a .3d
that `cavern` wrote, optionally converted by PROJ's `cs2cs`; the network is read by VTK.

usage: check_conditioned.py NETWORK.vtp DUMP3D.txt [--to CRS] [--names OUT.txt]

Checks, each to 1 mm (CONDITION_TOLERANCE):
- every leg Survex keeps (not flagged SURFACE, DUPLICATE or SPLAY, not of zero length) is one edge
  of the network flagged observed = 1, with its two stations at their surveyed positions;
- no other edge is flagged observed = 1, and every observed node is labelled with a station name
  at that station's surveyed position;
- observed edges have generation 0, simulated edges generation >= 1.
With --names, writes "label x y z" of the observed nodes (repr of the doubles) so that two
members can be byte-compared. Exit 0 when all holds, 1 with a message otherwise.
"""
import subprocess
import sys

import vtk

CONDITION_TOLERANCE = 1e-3  # m: the "to 1 mm"


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


args = sys.argv[1:]
to_crs = names_out = None
if "--to" in args:
    i = args.index("--to")
    to_crs = args[i + 1]
    del args[i:i + 2]
if "--names" in args:
    i = args.index("--names")
    names_out = args[i + 1]
    del args[i:i + 2]
vtp, dump = args

# --- Survex's stations and legs ---
cs = None
stations = {}  # label -> xyz (underground and entrance stations)
legs = set()
prev = None
for line in open(dump):
    t = line.split()
    if not t:
        continue
    if t[0] == "CS":
        cs = t[1]
    elif t[0] == "MOVE":
        prev = tuple(float(v) for v in t[1:4])
    elif t[0] == "LINE":
        cur = tuple(float(v) for v in t[1:4])
        if not any(f in t for f in ("SURFACE", "DUPLICATE", "SPLAY")) and cur != prev:
            legs.add(tuple(sorted((prev, cur))))
        prev = cur
    elif t[0] == "NODE" and "SURFACE" not in t:
        label = line[line.index("[") + 1:line.index("]")]
        stations[label] = tuple(float(v) for v in t[1:4])

if to_crs:
    pts = sorted({p for leg in legs for p in leg} | set(stations.values()))
    text = "".join("%.3f %.3f %.3f\n" % p for p in pts)
    out = subprocess.run(["cs2cs", "-f", "%.6f", cs, to_crs], input=text, capture_output=True,
                         text=True, check=True).stdout.split("\n")
    conv = {}
    for p, row in zip(pts, out):
        v = row.split()
        conv[p] = (float(v[0]), float(v[1]), float(v[2]))
    legs = {tuple(conv[p] for p in leg) for leg in legs}
    stations = {k: conv[p] for k, p in stations.items()}

# --- the network ---
r = vtk.vtkXMLPolyDataReader()
r.SetFileName(vtp)
r.Update()
pd = r.GetOutput()
if pd.GetNumberOfPoints() == 0:
    fail("%s: no points" % vtp)
cobs = pd.GetCellData().GetArray("observed")
cgen = pd.GetCellData().GetArray("generation")
pobs = pd.GetPointData().GetArray("observed")
plab = pd.GetPointData().GetAbstractArray("label")
if cobs is None or cgen is None or pobs is None or plab is None:
    fail("%s lacks observed / generation / label arrays" % vtp)


def key(p):  # positions to 1 mm
    return tuple(round(c / CONDITION_TOLERANCE) for c in p)


want = {}
for a, b in legs:
    want[tuple(sorted((key(a), key(b))))] = (a, b)
seen = set()
n_obs = 0
ids = vtk.vtkIdList()
for c in range(pd.GetNumberOfCells()):
    pd.GetCellPoints(c, ids)
    if ids.GetNumberOfIds() != 2:
        fail("cell %d is not a segment" % c)
    p, q = pd.GetPoint(ids.GetId(0)), pd.GetPoint(ids.GetId(1))
    if cobs.GetValue(c) != 0:
        n_obs += 1
        if cgen.GetValue(c) != 0:
            fail("observed edge %d has generation %g" % (c, cgen.GetValue(c)))
        k = tuple(sorted((key(p), key(q))))
        if k not in want:
            # rounding can split a point that lies at a half-millimetre: compare by distance
            best = min(want.values(), key=lambda l: max(
                min(max(abs(l[0][i] - p[i]) for i in range(3)), max(abs(l[1][i] - p[i]) for i in range(3))),
                min(max(abs(l[0][i] - q[i]) for i in range(3)), max(abs(l[1][i] - q[i]) for i in range(3)))))
            d = max(min(max(abs(best[0][i] - p[i]) for i in range(3)), max(abs(best[1][i] - p[i]) for i in range(3))),
                    min(max(abs(best[0][i] - q[i]) for i in range(3)), max(abs(best[1][i] - q[i]) for i in range(3))))
            if d > CONDITION_TOLERANCE:
                fail("observed edge %d %s-%s is no surveyed leg (nearest %.4f m off)" % (c, p, q, d))
            k = tuple(sorted((key(best[0]), key(best[1]))))
        seen.add(k)
    elif not cgen.GetValue(c) >= 1:
        fail("simulated edge %d has generation %g" % (c, cgen.GetValue(c)))
missing = [v for k, v in want.items() if k not in seen]
if missing:
    fail("%d of the %d surveyed legs are not in the network, e.g. %s" % (len(missing), len(want),
                                                                         missing[0]))
if n_obs != len(want):
    fail("%d edges are flagged observed, the survey has %d legs" % (n_obs, len(want)))

lines = []
n_named = 0
for v in range(pd.GetNumberOfPoints()):
    if not pobs.GetValue(v):
        continue
    label = plab.GetValue(v)
    p = pd.GetPoint(v)
    lines.append("%s %r %r %r\n" % (label, p[0], p[1], p[2]))
    if label in stations:
        s = stations[label]
        d = max(abs(s[i] - p[i]) for i in range(3))
        if d > CONDITION_TOLERANCE:
            fail("station %s is at %s in the network, at %s by Survex: %.4f m apart" % (label, p, s, d))
        n_named += 1
    else:
        fail("observed node %d is labelled '%s', which is no station of the survey" % (v, label))
if names_out:
    with open(names_out, "w") as f:
        f.writelines(sorted(lines))
print("ok: %d surveyed legs and %d named stations in %s to 1 mm%s" %
      (len(want), n_named, vtp, (" (converted to %s by cs2cs)" % to_crs) if to_crs else ""))
