"""Render a karst mesh (.vtp of `karst mesh`) coloured by tunnel type, headless.

The colours and names are karst's palette (include/karst/palette.h), read from the ParaView
script karst writes beside every mesh (STEM.paraview.py), so the picture matches ParaView, the
HTML report and the QGIS styles.

Usage: xvfb-run -a /usr/bin/python3 analysis/render_mesh.py MESH.vtp OUT.png [--title T]
           [--camera DX,DY,DZ] [--zoom Z] [--size W,H]
(python3-vtk9; off-screen rendering under Xvfb). The camera looks at the mesh's centre from
DX, DY, DZ times the mesh's horizontal span away (default 0.35,-0.9,0.8: from the south-south-
east, above), z up.
"""
import argparse
import os

import vtk


def karst_palette(mesh):
    """(code, name, (r, g, b)) of every tunnel type, from the script beside @mesh."""
    script = os.path.splitext(mesh)[0] + '.paraview.py'
    head = open(script, encoding='utf-8').read().split('# ----------', 1)[0]
    env = {}
    exec(compile(head, script, 'exec'), env)  # the data part: literals only
    return env['ARRAYS']['tunnel_type']['categories']


def triple(text, kind=float):
    return [kind(v) for v in text.split(',')]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('mesh')
    ap.add_argument('out')
    ap.add_argument('--title', default='')
    ap.add_argument('--camera', default='0.35,-0.9,0.8', type=triple)
    ap.add_argument('--zoom', default=1.3, type=float)
    ap.add_argument('--size', default='1600,1000', type=lambda s: triple(s, int))
    a = ap.parse_args()
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(a.mesh)
    reader.Update()
    pd = reader.GetOutput()
    pd.GetCellData().SetActiveScalars('tunnel_type')
    lo, hi = pd.GetCellData().GetArray('tunnel_type').GetRange()
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(pd)
    normals.ComputeCellNormalsOff()
    normals.SplittingOff()
    # Categories as ParaView's scripts show them: codes >= 0 always, "no type" only where used.
    cats = [c for c in karst_palette(a.mesh) if c[0] >= 0 or lo <= c[0] <= hi]
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(len(cats))
    for i, (code, name, rgb) in enumerate(cats):
        lut.SetTableValue(i, rgb[0], rgb[1], rgb[2], 1)
        lut.SetAnnotation(vtk.vtkVariant(code), name)
    lut.IndexedLookupOn()
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    mapper.SetLookupTable(lut)
    mapper.SetScalarModeToUseCellData()
    mapper.UseLookupTableScalarRangeOn()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetSpecular(0.2)
    actor.GetProperty().SetSpecularPower(20)
    ren = vtk.vtkRenderer()
    ren.AddActor(actor)
    ren.SetBackground(1, 1, 1)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle('tunnel type')
    bar.SetMaximumWidthInPixels(160)
    bar.SetMaximumHeightInPixels(420)
    for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty(),
              bar.GetAnnotationTextProperty()):
        p.SetColor(0, 0, 0)
        p.SetFontSize(14)
    bar.SetPosition(0.07, 0.55)
    bar.SetPosition2(0.12, 0.42)
    ren.AddActor2D(bar)
    if a.title:
        text = vtk.vtkTextActor()
        text.SetInput(a.title)
        text.GetTextProperty().SetColor(0, 0, 0)
        text.GetTextProperty().SetFontSize(20)
        text.SetPosition(20, 20)
        ren.AddActor2D(text)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(*a.size)
    cam = ren.GetActiveCamera()
    cam.SetViewUp(0, 0, 1)
    b = pd.GetBounds()
    c = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
    span = max(b[1] - b[0], b[3] - b[2])
    cam.SetFocalPoint(*c)
    cam.SetPosition(*[c[k] + a.camera[k] * span for k in range(3)])
    ren.ResetCamera()
    cam.Zoom(a.zoom)
    win.Render()
    w2i = vtk.vtkWindowToImageFilter()
    w2i.SetInput(win)
    w2i.Update()
    png = vtk.vtkPNGWriter()
    png.SetFileName(a.out)
    png.SetInputConnection(w2i.GetOutputPort())
    png.Write()
    print('wrote', a.out, pd.GetNumberOfCells(), 'triangles')


if __name__ == '__main__':
    main()
