"""Render block tiles (DIR/tiles/TYPE.vtp from `karst blocks`) side by side, each block in its own
colour (cell array block_id), headless.

Usage: xvfb-run -a /usr/bin/python3 docs/blocks_render.py OUT.png TILE.vtp [TILE.vtp ...]
(python3-vtk9; off-screen rendering under Xvfb)."""
import os
import sys
import vtk

out, paths = sys.argv[1], sys.argv[2:]
cols = 3 if len(paths) > 2 else len(paths)
rows = (len(paths) + cols - 1) // cols
win = vtk.vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(420 * cols, 420 * rows)
for k, path in enumerate(paths):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    pd = r.GetOutput()
    pd.GetCellData().SetActiveScalars("block_id")
    n = int(pd.GetCellData().GetArray("block_id").GetRange()[1]) + 1
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(n)
    lut.SetTableRange(0, n - 1)
    rnd = vtk.vtkMinimalStandardRandomSequence()
    rnd.SetSeed(7)
    for i in range(n):
        c = []
        for _ in range(3):
            rnd.Next()
            c.append(0.45 + 0.5 * rnd.GetValue())
        lut.SetTableValue(i, c[0], c[1] * 0.9, c[2] * 0.8, 1)
    lut.Build()
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(pd)
    normals.SplittingOff()
    m = vtk.vtkPolyDataMapper()
    m.SetInputConnection(normals.GetOutputPort())
    m.SetLookupTable(lut)
    m.SetScalarModeToUseCellData()
    m.SetScalarRange(0, n - 1)
    a = vtk.vtkActor()
    a.SetMapper(m)
    ren = vtk.vtkRenderer()
    ren.AddActor(a)
    ren.SetBackground(1, 1, 1)
    x, y = k % cols, rows - 1 - k // cols
    ren.SetViewport(x / cols, y / rows, (x + 1) / cols, (y + 1) / rows)
    cam = ren.GetActiveCamera()
    cam.SetPosition(60, -45, 40)
    cam.SetFocalPoint(10, 10, 10)
    cam.SetViewUp(0, 0, 1)
    ren.ResetCamera()
    cam.Zoom(1.25)
    t = vtk.vtkTextActor()
    t.SetInput(os.path.basename(path).replace(".vtp", ""))
    t.GetTextProperty().SetColor(0, 0, 0)
    t.GetTextProperty().SetFontSize(20)
    t.SetPosition(10, 10)
    ren.AddActor2D(t)
    win.AddRenderer(ren)
win.Render()
w2i = vtk.vtkWindowToImageFilter()
w2i.SetInput(win)
w2i.Update()
png = vtk.vtkPNGWriter()
png.SetFileName(out)
png.SetInputConnection(w2i.GetOutputPort())
png.Write()
