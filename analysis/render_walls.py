"""Render a karst mesh close-up (.ply from `karst mesh` or bench_mesh's scenes), headless.

Usage: xvfb-run -a /usr/bin/python3 analysis/render_walls.py MESH.ply OUT.png
           --eye X,Y,Z --at X,Y,Z [--up 0,0,1] [--angle 50] [--color rock|type|feature]
           [--title TEXT] [--size 1400x900] [--beside MESH2.ply --title2 TEXT]
(python3-vtk9, off-screen under Xvfb). The camera sits at --eye looking at --at; --angle is
the vertical field of view in degrees. Colours: "rock" a limestone grey with a headlight (for
views from inside a conduit), "type" the tunnel-type palette of render_mesh.py, "feature" walls
grey and speleothems amber. The PLY faces carry int tunnel_type and int feature (karst's
writer); both are optional here."""
import argparse
import array
import struct

import vtk

ap = argparse.ArgumentParser()
ap.add_argument("mesh")
ap.add_argument("out")
ap.add_argument("--eye", required=True)
ap.add_argument("--at", required=True)
ap.add_argument("--up", default="0,0,1")
ap.add_argument("--angle", type=float, default=50)
ap.add_argument("--color", default="rock", choices=["rock", "type", "feature"])
ap.add_argument("--title", default="")
ap.add_argument("--size", default="1400x900")
ap.add_argument("--beside", default="", help="a second mesh, drawn in the right half")
ap.add_argument("--title2", default="")
args = ap.parse_args()
vec = lambda s: [float(v) for v in s.split(",")]

def scene(path, title):
    """A renderer drawing the mesh at @p path, coloured by --color, with @p title."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().split("\n")
    nv = nf = 0
    props = []
    in_face = False
    for line in head:
        if line.startswith("element vertex"):
            nv = int(line.split()[2])
        if line.startswith("element face"):
            nf, in_face = int(line.split()[2]), True
        if in_face and line.startswith("property int "):
            props.append(line.split()[2])
    xyz = array.array("d")
    xyz.frombytes(data[end:end + 24 * nv])
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    pts.SetNumberOfPoints(nv)
    for i in range(nv):
        pts.SetPoint(i, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2])
    cells = vtk.vtkCellArray()
    arrays = {}
    for p in props:
        arrays[p] = vtk.vtkIntArray()
        arrays[p].SetName(p)
    rec = struct.Struct("<Biii" + "i" * len(props))
    off = end + 24 * nv
    for f in rec.iter_unpack(data[off:off + rec.size * nf]):
        cells.InsertNextCell(3)
        for k in (1, 2, 3):
            cells.InsertCellPoint(f[k])
        for j, p in enumerate(props):
            arrays[p].InsertNextValue(f[4 + j])
    pd = vtk.vtkPolyData()
    pd.SetPoints(pts)
    pd.SetPolys(cells)
    for a in arrays.values():
        pd.GetCellData().AddArray(a)
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(pd)
    normals.ComputeCellNormalsOff()
    normals.SplittingOff()
    normals.ConsistencyOff()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    ren = vtk.vtkRenderer()
    if args.color == "rock":
        mapper.ScalarVisibilityOff()
        prop.SetColor(0.80, 0.76, 0.68)
        prop.SetAmbient(0.25)
        prop.SetDiffuse(0.85)
        prop.SetSpecular(0.15)
        prop.SetSpecularPower(15)
        ren.SetBackground(0.05, 0.05, 0.06)
    else:
        lut = vtk.vtkLookupTable()
        if args.color == "type":
            names = ["tube", "keyhole", "canyon", "bed", "passage", "epikarst", "chamber"]
            colors = [(0.90, 0.60, 0.20), (0.30, 0.60, 0.90), (0.85, 0.30, 0.30), (0.40, 0.75, 0.40),
                      (0.75, 0.55, 0.85), (0.95, 0.85, 0.30), (0.55, 0.55, 0.55)]
            field = "tunnel_type"
        else:
            names = ["wall", "speleothem"]
            colors = [(0.72, 0.70, 0.66), (0.95, 0.62, 0.20)]
            field = "feature"
        lut.SetNumberOfTableValues(len(colors))
        lut.SetTableRange(0, len(colors) - 1)
        for i, c in enumerate(colors):
            lut.SetTableValue(i, c[0], c[1], c[2], 1)
            lut.SetAnnotation(i, names[i])
        lut.IndexedLookupOn()
        lut.SetNanColor(0.35, 0.35, 0.38, 1)  # -1: the clipping box
        pd.GetCellData().SetActiveScalars(field)
        mapper.SetLookupTable(lut)
        mapper.SetScalarModeToUseCellData()
        mapper.UseLookupTableScalarRangeOn()
        prop.SetSpecular(0.2)
        ren.SetBackground(1, 1, 1)
    ren.AddActor(actor)
    light = vtk.vtkLight()
    light.SetLightTypeToHeadlight()
    ren.AddLight(light)
    if title:
        text = vtk.vtkTextActor()
        text.SetInput(title)
        text.GetTextProperty().SetColor(*((1, 1, 1) if args.color == "rock" else (0, 0, 0)))
        text.GetTextProperty().SetFontSize(22)
        text.GetTextProperty().SetBackgroundColor(*((0, 0, 0) if args.color == "rock" else (1, 1, 1)))
        text.GetTextProperty().SetBackgroundOpacity(0.7)
        text.SetPosition(20, 20)
        ren.AddActor2D(text)

    return ren, pd


w, h = (int(v) for v in args.size.split("x"))
win = vtk.vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(w, h)
views = [(args.mesh, args.title)] + ([(args.beside, args.title2)] if args.beside else [])
nf = 0
for i, (path, title) in enumerate(views):
    ren, pd = scene(path, title)
    nf += pd.GetNumberOfCells()
    ren.SetViewport(i / len(views), 0, (i + 1) / len(views), 1)
    win.AddRenderer(ren)
    cam = ren.GetActiveCamera()
    cam.SetPosition(*vec(args.eye))
    cam.SetFocalPoint(*vec(args.at))
    cam.SetViewUp(*vec(args.up))
    cam.SetViewAngle(args.angle)
    ren.ResetCameraClippingRange()
win.Render()
w2i = vtk.vtkWindowToImageFilter()
w2i.SetInput(win)
w2i.Update()
png = vtk.vtkPNGWriter()
png.SetFileName(args.out)
png.SetInputConnection(w2i.GetOutputPort())
png.Write()
print("wrote", args.out, nf, "triangles")
