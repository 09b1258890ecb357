"""Render a karst mesh (.vtp from `karst mesh`) coloured by tunnel type, headless.

Usage: xvfb-run -a /usr/bin/python3 analysis/render_mesh.py MESH.vtp OUT.png [TITLE]
(python3-vtk9; off-screen rendering under Xvfb)."""
import sys
import vtk

path, out = sys.argv[1], sys.argv[2]
title = sys.argv[3] if len(sys.argv) > 3 else ""
reader = vtk.vtkXMLPolyDataReader()
reader.SetFileName(path)
reader.Update()
pd = reader.GetOutput()
pd.GetCellData().SetActiveScalars("tunnel_type")
normals = vtk.vtkPolyDataNormals()
normals.SetInputData(pd)
normals.ComputeCellNormalsOff()
normals.SplittingOff()
names = ["tube", "keyhole", "canyon", "bed", "passage", "epikarst", "chamber"]
colors = [(0.90, 0.60, 0.20), (0.30, 0.60, 0.90), (0.85, 0.30, 0.30), (0.40, 0.75, 0.40),
          (0.75, 0.55, 0.85), (0.95, 0.85, 0.30), (0.55, 0.55, 0.55)]
lut = vtk.vtkLookupTable()
lut.SetNumberOfTableValues(7)
lut.SetTableRange(0, 6)
for i, c in enumerate(colors):
    lut.SetTableValue(i, c[0], c[1], c[2], 1)
    lut.SetAnnotation(i, names[i])
lut.IndexedLookupOn()
mapper = vtk.vtkPolyDataMapper()
mapper.SetInputConnection(normals.GetOutputPort())
mapper.SetLookupTable(lut)
mapper.SetScalarModeToUseCellData()
mapper.UseLookupTableScalarRangeOn()
actor = vtk.vtkActor()
actor.SetMapper(mapper)
actor.GetProperty().SetSpecular(0.2)
ren = vtk.vtkRenderer()
ren.AddActor(actor)
ren.SetBackground(1, 1, 1)
bar = vtk.vtkScalarBarActor()
bar.SetLookupTable(lut)
bar.SetTitle("tunnel type")
for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty(), bar.GetAnnotationTextProperty()):
    p.SetColor(0, 0, 0)
    p.SetFontSize(14)
bar.SetPosition(0.07, 0.55)
bar.SetPosition2(0.12, 0.42)
ren.AddActor2D(bar)
if title:
    text = vtk.vtkTextActor()
    text.SetInput(title)
    text.GetTextProperty().SetColor(0, 0, 0)
    text.GetTextProperty().SetFontSize(20)
    text.SetPosition(20, 20)
    ren.AddActor2D(text)
win = vtk.vtkRenderWindow()
win.SetOffScreenRendering(1)
win.AddRenderer(ren)
win.SetSize(1600, 1000)
cam = ren.GetActiveCamera()
cam.SetViewUp(0, 0, 1)
b = pd.GetBounds()
c = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
span = max(b[1] - b[0], b[3] - b[2])
cam.SetFocalPoint(*c)
cam.SetPosition(c[0] + 0.35 * span, c[1] - 0.9 * span, c[2] + 0.8 * span)
ren.ResetCamera()
cam.Zoom(1.3)
win.Render()
w2i = vtk.vtkWindowToImageFilter()
w2i.SetInput(win)
w2i.Update()
png = vtk.vtkPNGWriter()
png.SetFileName(out)
png.SetInputConnection(w2i.GetOutputPort())
png.Write()
print("wrote", out, pd.GetNumberOfCells(), "triangles")
