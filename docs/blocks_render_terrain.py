"""Render an amplified terrain (DIR/terrain_blocks.vtp from `karst blocks`, cell arrays block_id
and block_type) or a carved mesh from `karst mesh --carve --blocks` (coloured by tunnel_type),
headless, looking at a gorge wall.

Usage: xvfb-run -a /usr/bin/python3 docs/blocks_render_terrain.py MESH.vtp OUT.png
           [--camera X,Y,Z --focus X,Y,Z] [--title TEXT]
(python3-vtk9; off-screen rendering under Xvfb)."""
import sys
import vtk

args = sys.argv[1:]
path, out = args[0], args[1]
cam_pos, focus, title = (100, -40, 190), (100, 60, 100), ""
i = 2
while i < len(args):
    if args[i] == "--camera":
        cam_pos = tuple(float(v) for v in args[i + 1].split(",")); i += 2
    elif args[i] == "--focus":
        focus = tuple(float(v) for v in args[i + 1].split(",")); i += 2
    elif args[i] == "--title":
        title = args[i + 1]; i += 2
    else:
        sys.exit("unknown argument " + args[i])
r = vtk.vtkXMLPolyDataReader()
r.SetFileName(path)
r.Update()
pd = r.GetOutput()
cd = pd.GetCellData()
# colour: block_type when present (-1 terrain), else tunnel_type (-1 rock)
name = "block_type" if cd.GetArray("block_type") else "tunnel_type"
arr = cd.GetArray(name)
colors = vtk.vtkUnsignedCharArray()
colors.SetNumberOfComponents(3)
colors.SetName("rgb")
palette = {-1: (176, 170, 160), 0: (214, 160, 98), 1: (190, 120, 90), 2: (150, 150, 120),
           3: (200, 110, 110), 4: (120, 150, 200), 5: (160, 190, 120)}
ids = cd.GetArray("block_id")
for c in range(pd.GetNumberOfCells()):
    v = int(arr.GetValue(c)) if arr else -1
    if name == "tunnel_type":
        rgb = (176, 170, 160) if v < 0 else (230, 80, 60)
    else:
        rgb = palette.get(v, (200, 200, 200))
        if v >= 0 and ids is not None:  # a little variation from block to block
            k = (int(ids.GetValue(c)) * 2654435761) % 97 / 97.0 - 0.5
            rgb = tuple(max(0, min(255, int(x * (1 + 0.25 * k)))) for x in rgb)
    colors.InsertNextTuple3(*rgb)
cd.AddArray(colors)
cd.SetActiveScalars("rgb")
normals = vtk.vtkPolyDataNormals()
normals.SetInputData(pd)
normals.SplittingOff()
m = vtk.vtkPolyDataMapper()
m.SetInputConnection(normals.GetOutputPort())
m.SetScalarModeToUseCellData()
m.SetColorModeToDirectScalars()
a = vtk.vtkActor()
a.SetMapper(m)
ren = vtk.vtkRenderer()
ren.AddActor(a)
ren.SetBackground(0.85, 0.9, 0.97)
light = vtk.vtkLight()
light.SetPosition(cam_pos[0] - 80, cam_pos[1], cam_pos[2] + 150)
light.SetFocalPoint(*focus)
ren.AddLight(light)
cam = ren.GetActiveCamera()
cam.SetPosition(*cam_pos)
cam.SetFocalPoint(*focus)
cam.SetViewUp(0, 0, 1)
if title:
    t = vtk.vtkTextActor()
    t.SetInput(title)
    t.GetTextProperty().SetColor(0, 0, 0)
    t.GetTextProperty().SetFontSize(20)
    t.SetPosition(10, 10)
    ren.AddActor2D(t)
win = vtk.vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(1200, 800)
win.AddRenderer(ren)
win.Render()
w2i = vtk.vtkWindowToImageFilter()
w2i.SetInput(win)
w2i.Update()
png = vtk.vtkPNGWriter()
png.SetFileName(out)
png.SetInputConnection(w2i.GetOutputPort())
png.Write()
