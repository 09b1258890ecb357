#!/usr/bin/python3
"""Independent check of the VTK files written by tests/unit/test_vtk.c.

Run with /usr/bin/python3 (Debian's python3-vtk9): VTK's own readers, the
ones ParaView uses, open each file; the expected values are the fixture's
hand-chosen values (repeated here on purpose, not read from the C side).
Also checks the raw XML: every DataArray/Array is format="binary" (inline)
and there is no <AppendedData> (Debian's ParaView 5.11 reads 0 points from
appended data), and parses the .pvd with Python's own XML parser.

Usage: check_vtk.py DIR     (exit 0 when every check passes)
"""
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLPolyDataReader

DIR = sys.argv[1]
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)


def same(a, b):
    return (math.isnan(a) and math.isnan(b)) or a == b


def raw_checks(name):
    with open(os.path.join(DIR, name), "rb") as f:
        head = f.read()
    check(b"<AppendedData" not in head, f"{name}: has <AppendedData>")
    tags = re.findall(rb"<(?:DataArray|Array)\b[^>]*>", head)
    check(len(tags) > 0, f"{name}: no data arrays")
    for t in tags:
        check(b'format="binary"' in t, f"{name}: array not inline binary: {t[:120]!r}")


def read_poly(name):
    raw_checks(name)
    r = vtkXMLPolyDataReader()
    r.SetFileName(os.path.join(DIR, name))
    r.Update()
    check(r.GetErrorCode() == 0, f"{name}: reader error {r.GetErrorCode()}")
    return r.GetOutput()


def strings(fd, name):
    a = fd.GetAbstractArray(name)
    if a is None:
        return None
    return [a.GetValue(i) for i in range(a.GetNumberOfValues())]


TUNNEL_TYPES = ["tube", "keyhole", "canyon", "bed", "passage", "epikarst", "chamber"]
NODE_KINDS = ["interior", "sink", "spring", "waypoint", "junction", "amplification"]

# ---- network.vtp: the fixture of test_vtk.c ---------------------------------
xyz = [(0, 0, 0), (10.5, 0, -2.25), (1.0 / 3.0, 4512345.678901234, -1234.5), (20, 5, -3),
       (100, 100, 100), (101, 100, 100), (200, -1e-7, 0.1)]
edges = [(0, 1), (1, 2), (1, 3), (4, 5)]
kind = [1, 4, 0, 2, 1, 2, 3]
dwt = [-0.5, 1e-3, 2.5, float("nan"), 0, 1e6, -7.125]
tunnel = [0, 1, 6, 2]
radius = [0.5, 1.25, 3.999, 0.5]
lrud = [(1, 2, 3, 4), (0.5, 0.5, 1, 1), (0, 0, 0, 0), (9, 8, 7, 6)]
labels = ["entrance", "1.2", "", 'a&b<c>"q"', "\u00fcn\u00efcode", "", "far"]

pd = read_poly("network.vtp")
check(pd.GetNumberOfPoints() == 7, f"network: {pd.GetNumberOfPoints()} points, expected 7")
check(pd.GetNumberOfLines() == 4, f"network: {pd.GetNumberOfLines()} lines, expected 4")
check(pd.GetNumberOfCells() == 4, "network: cells other than lines")
check(pd.GetPoints().GetDataType() == 11, "network: points are not Float64")  # VTK_DOUBLE
for i, p in enumerate(xyz):
    check(pd.GetPoint(i) == p, f"network: point {i} = {pd.GetPoint(i)}, expected {p}")
for e, (u, v) in enumerate(edges):
    c = pd.GetCell(e)
    ids = (c.GetPointId(0), c.GetPointId(1))
    check(c.GetNumberOfPoints() == 2 and ids == (u, v), f"network: cell {e} = {ids}")
ptd, cd = pd.GetPointData(), pd.GetCellData()
k = ptd.GetArray("kind")
check(k is not None and k.GetClassName() == "vtkIntArray", "network: kind is not an Int32 array")
if k is not None:
    check([k.GetValue(i) for i in range(7)] == kind, "network: kind values")
w = ptd.GetArray("water_table_distance")
check(w is not None and w.GetClassName() == "vtkDoubleArray", "network: water_table_distance")
if w is not None:
    check(all(same(w.GetValue(i), dwt[i]) for i in range(7)), "network: water_table_distance values")
lab = ptd.GetAbstractArray("label")
check(lab is not None and lab.GetClassName() == "vtkStringArray", "network: label array")
if lab is not None:
    got = [lab.GetValue(i) for i in range(lab.GetNumberOfValues())]
    check(got == labels, f"network: labels {got}")
t = cd.GetArray("tunnel_type")
check(t is not None and t.GetClassName() == "vtkIntArray", "network: tunnel_type not Int32")
if t is not None:
    check([t.GetValue(i) for i in range(4)] == tunnel, "network: tunnel_type values")
check(cd.GetScalars() is not None and cd.GetScalars().GetName() == "tunnel_type",
      "network: tunnel_type is not the active cell scalar")
r = cd.GetArray("radius")
check(r is not None and [r.GetValue(i) for i in range(4)] == radius, "network: radius values")
l4 = cd.GetArray("lrud")
check(l4 is not None and l4.GetNumberOfComponents() == 4, "network: lrud components")
if l4 is not None:
    check([l4.GetTuple4(i) for i in range(4)] == [tuple(map(float, x)) for x in lrud],
          "network: lrud values")
fd = pd.GetFieldData()
check(strings(fd, "crs") == ["EPSG:27572"], f"network: crs {strings(fd, 'crs')}")
check(strings(fd, "title") == ["Grotte d'essai & <test>"], f"network: title {strings(fd, 'title')}")
check(strings(fd, "tunnel_type_names") == TUNNEL_TYPES, "network: tunnel_type_names")
check(strings(fd, "node_kind_names") == NODE_KINDS, "network: node_kind_names")

# ---- empty.vtp --------------------------------------------------------------
pd = read_poly("empty.vtp")
check(pd.GetNumberOfPoints() == 0 and pd.GetNumberOfCells() == 0, "empty: not empty")

# ---- samples.vtp ------------------------------------------------------------
pd = read_poly("samples.vtp")
check(pd.GetNumberOfPoints() == 4 and pd.GetNumberOfVerts() == 4, "samples: counts")
s = pd.GetPointData().GetArray("source")
check(s is not None and s.GetClassName() == "vtkIntArray", "samples: source not Int32")
if s is not None:
    check([s.GetValue(i) for i in range(4)] == [0, 1, 4, 2], "samples: source values")
check(strings(pd.GetFieldData(), "source_names") ==
      ["key_point", "horizon", "water_table", "permeability", "fill", "amplification", "prescribed_path",
       "survey", "points"],
      "samples: source_names")
nk = pd.GetFieldData().GetArray("n_key_points")
check(nk is not None and nk.GetValue(0) == 1, "samples: n_key_points")

# ---- mesh.vtp: a tetrahedron ------------------------------------------------
pd = read_poly("mesh.vtp")
check(pd.GetNumberOfPoints() == 4 and pd.GetNumberOfPolys() == 4, "mesh: counts")
tris = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
for i, tri in enumerate(tris):
    c = pd.GetCell(i)
    got = tuple(c.GetPointId(j) for j in range(c.GetNumberOfPoints()))
    check(got == tri, f"mesh: triangle {i} = {got}")
tt = pd.GetCellData().GetArray("tunnel_type")
check(tt is not None and [tt.GetValue(i) for i in range(4)] == [0, 1, 2, 6], "mesh: tunnel_type")
check(strings(pd.GetFieldData(), "tunnel_type_names") == TUNNEL_TYPES, "mesh: tunnel_type_names")

# ---- field.vti --------------------------------------------------------------
raw_checks("field.vti")
ir = vtkXMLImageDataReader()
ir.SetFileName(os.path.join(DIR, "field.vti"))
ir.Update()
img = ir.GetOutput()
check(img.GetDimensions() == (3, 2, 2), f"image: dims {img.GetDimensions()}")
check(img.GetOrigin() == (1.0, 2.0, 3.0), f"image: origin {img.GetOrigin()}")
check(img.GetSpacing() == (0.5, 0.5, 0.25), f"image: spacing {img.GetSpacing()}")
sc = img.GetPointData().GetScalars()
check(sc is not None and sc.GetName() == "sdf" and sc.GetClassName() == "vtkFloatArray",
      "image: scalars")
if sc is not None:
    for kk in range(2):
        for j in range(2):
            for i in range(3):
                pid = img.ComputePointId([i, j, kk])
                check(sc.GetValue(pid) == i + 10 * j + 100 * kk, f"image: value at {i},{j},{kk}")
    # the point at (i, j, k) = (2, 1, 1) lies at origin + spacing * index
    check(img.GetPoint(img.ComputePointId([2, 1, 1])) == (2.0, 2.5, 3.25), "image: geometry")

# ---- ensemble.pvd: Python's XML parser --------------------------------------
root = ET.parse(os.path.join(DIR, "ensemble.pvd")).getroot()
check(root.tag == "VTKFile" and root.get("type") == "Collection", "pvd: root")
ds = root.findall("./Collection/DataSet")
check([d.get("file") for d in ds] == ["realisations/0000/network.vtp", "a&b.vtp", "q\"'<>.vtp"],
      f"pvd: files {[d.get('file') for d in ds]}")
check([d.get("timestep") for d in ds] == ["0", "1", "2"], "pvd: timesteps")
root = ET.parse(os.path.join(DIR, "empty.pvd")).getroot()
check(len(root.findall("./Collection/DataSet")) == 0 and root.find("Collection") is not None,
      "empty pvd")

for f in failures:
    print("FAIL:", f)
print(f"check_vtk.py: {len(failures)} failure(s)")
sys.exit(1 if failures else 0)
