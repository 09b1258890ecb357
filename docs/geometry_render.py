# Render a karst .ply mesh coloured by tunnel_type, headless (run under xvfb-run).
import struct, sys, array
import vtk
path, out = sys.argv[1], sys.argv[2]
data = open(path, 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
head = data[:end].decode().split('\n')
nv = nf = 0
for l in head:
    if l.startswith('element vertex'): nv = int(l.split()[2])
    if l.startswith('element face'): nf = int(l.split()[2])
xyz = array.array('d'); xyz.frombytes(data[end:end + 24 * nv])
pts = vtk.vtkPoints(); pts.SetDataTypeToDouble(); pts.SetNumberOfPoints(nv)
for i in range(nv): pts.SetPoint(i, xyz[3*i], xyz[3*i+1], xyz[3*i+2])
cells = vtk.vtkCellArray(); lab = vtk.vtkIntArray(); lab.SetName('tunnel_type')
off = end + 24 * nv
for (c, a, b, d, t, ft) in struct.iter_unpack('<Biiiii', data[off:off + 21 * nf]):
    cells.InsertNextCell(3); cells.InsertCellPoint(a); cells.InsertCellPoint(b); cells.InsertCellPoint(d)
    lab.InsertNextValue(t)
pd = vtk.vtkPolyData(); pd.SetPoints(pts); pd.SetPolys(cells); pd.GetCellData().SetScalars(lab)
normals = vtk.vtkPolyDataNormals(); normals.SetInputData(pd); normals.ComputeCellNormalsOff(); normals.SplittingOff()
names = ['tube', 'keyhole', 'canyon', 'bed', 'passage', 'epikarst', 'chamber']
colors = [(0.90,0.60,0.20),(0.30,0.60,0.90),(0.85,0.30,0.30),(0.40,0.75,0.40),(0.75,0.55,0.85),(0.95,0.85,0.30),(0.55,0.55,0.55)]
lut = vtk.vtkLookupTable(); lut.SetNumberOfTableValues(7); lut.SetTableRange(0, 6)
for i, c in enumerate(colors): lut.SetTableValue(i, c[0], c[1], c[2], 1); lut.SetAnnotation(i, names[i])
lut.IndexedLookupOn()
mapper = vtk.vtkPolyDataMapper(); mapper.SetInputConnection(normals.GetOutputPort())
mapper.SetLookupTable(lut); mapper.SetScalarModeToUseCellData(); mapper.UseLookupTableScalarRangeOn()
actor = vtk.vtkActor(); actor.SetMapper(mapper)
actor.GetProperty().SetSpecular(0.2); actor.GetProperty().SetSpecularPower(20)
ren = vtk.vtkRenderer(); ren.AddActor(actor); ren.SetBackground(1, 1, 1)
bar = vtk.vtkScalarBarActor(); bar.SetLookupTable(lut); bar.SetTitle('tunnel type')
bar.SetNumberOfLabels(7); bar.SetMaximumWidthInPixels(160); bar.SetMaximumHeightInPixels(420)
for p in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty(), bar.GetAnnotationTextProperty()):
    p.SetColor(0, 0, 0); p.SetFontSize(14)
bar.SetTextPositionToSucceedScalarBar(); bar.SetPosition(0.09, 0.55); bar.SetPosition2(0.12, 0.42); ren.AddActor2D(bar)
win = vtk.vtkRenderWindow(); win.SetOffScreenRendering(1); win.AddRenderer(ren); win.SetSize(1400, 900)
cam = ren.GetActiveCamera(); cam.SetViewUp(0, 0, 1)
b = pd.GetBounds(); c = [(b[0]+b[1])/2, (b[2]+b[3])/2, (b[4]+b[5])/2]
cam.SetFocalPoint(*c); cam.SetPosition(c[0] + 20, c[1] - 40, c[2] + 45)
ren.ResetCamera(); cam.Zoom(1.45)
win.Render()
w2i = vtk.vtkWindowToImageFilter(); w2i.SetInput(win); w2i.Update()
png = vtk.vtkPNGWriter(); png.SetFileName(out); png.SetInputConnection(w2i.GetOutputPort()); png.Write()
print('wrote', out, nf, 'triangles')
