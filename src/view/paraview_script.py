# ---------------------------------------------------------------------------------------------
# The part below is the same in every script karst writes (src/view/paraview_script.py).
#
# It loads FILES, gives every categorical array an annotated categorical lookup table (the
# category names from the file's "*_names" field data, the colours of karst's palette) and
# every continuous array the palette's ramp and a colour bar titled with its quantity and
# unit, then shows each file as its role asks, on a white background, north up.
#
# Options (pvpython / pvbatch only; paraview --script passes none):
#   --screenshot FILE.png   save the view (1200 x 800 unless --size W H)
#   --legend FILE.json      save what each lookup table and colour bar holds (for tests)
#   --show ROLE[,ROLE...]   show only the files of these roles (network, samples, mesh,
#                           field, collection, geology; samples and geology are hidden at start)
# ---------------------------------------------------------------------------------------------
import json
import math
import os
import sys

from paraview.simple import (ColorBy, Contour, GetActiveViewOrCreate, GetColorTransferFunction,
                             GetScalarBar, Hide, OpenDataFile, Render, SaveScreenshot, Show,
                             Slice, Text, Threshold)

# paraview --script gives a script no __file__: `karst view` starts ParaView in its directory.
HERE = os.path.dirname(os.path.abspath(__file__)) if '__file__' in globals() else os.getcwd()
# Shown only when asked (the eye icon of ParaView's pipeline browser): they would hide the rest.
HIDDEN_AT_START = ('samples', 'geology')
# Colour bars, in this order (the orientation axes sit in the lower left corner).
CORNERS = ['Lower Right Corner', 'Upper Right Corner', 'Upper Left Corner', 'Lower Left Corner']


def parse_options(argv):
    opts = {'screenshot': None, 'legend': None, 'size': [1200, 800], 'show': None}
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ('--screenshot', '--legend') and i + 1 < len(argv):
            opts[a[2:]] = argv[i + 1]
            i += 1
        elif a == '--show' and i + 1 < len(argv):
            opts['show'] = argv[i + 1].split(',')
            i += 1
        elif a == '--size' and i + 2 < len(argv):
            opts['size'] = [int(argv[i + 1]), int(argv[i + 2])]
            i += 2
        i += 1
    return opts


def file_strings(source, name):
    """The values of the field-data string array @name of @source's output, or None (a
    remote server, or no such array): read on the client, where pvbatch and paraview keep
    the data."""
    try:
        data = source.GetClientSideObject().GetOutputDataObject(0)
        array = data.GetFieldData().GetAbstractArray(name)
        if array is None:
            return None
        return [array.GetValue(i) for i in range(array.GetNumberOfValues())]
    except Exception:
        return None


def file_unit(source, name):
    """The unit the file states for array @name (its row of the "array_units" table)."""
    rows = file_strings(source, 'array_units')
    if rows:
        for i in range(0, len(rows) - 2, 3):
            if rows[i] == name:
                return rows[i + 1]
    return None


def spec_for(name, role):
    """What karst's dictionary says of array @name in a file of kind @role."""
    return ROLE_ARRAYS.get(role, {}).get(name) or ARRAYS.get(name)


def arrays_of(source):
    """(association, name, range) of every numeric point and cell array."""
    out = []
    for assoc, coll in (('POINTS', source.PointData), ('CELLS', source.CellData)):
        for name in coll.keys():
            info = coll[name]
            try:
                lo, hi = info.GetRange(-1 if info.GetNumberOfComponents() > 1 else 0)
            except Exception:
                continue
            if (ARRAYS.get(name) or {}).get('unit') == 'text':
                continue
            out.append((assoc, name, (lo, hi)))
    return out


def categorical_lut(name, spec, names, lo, hi):
    lut = GetColorTransferFunction(name)
    lut.InterpretValuesAsCategories = 1
    lut.AnnotationsInitialized = 1
    annotations, colours, seen = [], [], set()
    for code, label, rgb in spec['categories']:
        if code < 0 and not (lo <= code <= hi):  # "none" categories only where they occur
            continue
        if names is not None and 0 <= code < len(names) and names[code]:
            label = names[code]
        annotations += [str(code), label]
        colours += list(rgb)
        seen.add(code)
    # Categories the file names but the palette does not list (springs ...): in turn.
    for code, label in enumerate(names or []):
        if code not in seen and label:
            annotations += [str(code), label]
            colours += list(CYCLE[code % len(CYCLE)])
    lut.Annotations = annotations
    lut.IndexedColors = colours
    lut.IndexedOpacities = [1.0] * (len(colours) // 3)
    lut.NanColor = list(NEUTRAL)
    return lut


def continuous_lut(name, colouring, lo, hi):
    lut = GetColorTransferFunction(name)
    if colouring == 'diverging':  # symmetric about 0, so that 0 is the middle grey
        m = max(abs(lo), abs(hi))
        lo, hi = -m, m
    if not (hi > lo):
        lo, hi = lo - 0.5, lo + 0.5
    points = []
    for t, r, g, b in RAMPS[colouring]:
        points += [lo + t * (hi - lo), r, g, b]
    lut.ColorSpace = 'RGB'  # the palette interpolates in sRGB
    lut.RGBPoints = points
    lut.AutomaticRescaleRangeMode = 'Never'
    lut.NanColor = list(NEUTRAL)
    return lut


def style_bar(bar, title):
    bar.Title = title
    bar.ComponentTitle = ''
    bar.TitleColor = list(FOREGROUND)
    bar.LabelColor = list(FOREGROUND)
    bar.TitleFontSize = 18
    bar.LabelFontSize = 15
    bar.ScalarBarLength = 0.4
    bar.RangeLabelFormat = '%.4g'
    bar.Visibility = 0


def setup_view():
    view = GetActiveViewOrCreate('RenderView')
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    view.Background = list(BACKGROUND)
    try:
        view.OrientationAxesLabelColor = list(FOREGROUND)
    except AttributeError:
        pass
    view.OrientationAxesVisibility = 1
    return view


def show_source(view, item, source):
    """Show @source as its role asks; returns the displays and the array coloured at start."""
    role, colour_by = item['role'], item['colour_by']
    arrays = {name: assoc for assoc, name, _ in arrays_of(source)}
    displays = []
    if role == 'field':
        name = colour_by or next(iter(arrays), None)
        outline = Show(source, view)
        outline.SetRepresentationType('Outline')
        outline.AmbientColor = outline.DiffuseColor = list(FOREGROUND)
        displays.append((outline, None))
        # The 0 isosurface is the surface a mesh of the same script already shows.
        if name and not any(f['role'] == 'mesh' for f in FILES):
            contour = Contour(Input=source, ContourBy=['POINTS', name], Isosurfaces=[0.0])
            surface = Show(contour, view)
            surface.DiffuseColor = list(WALL)
            surface.Opacity = 0.5
            ColorBy(surface, None)
            displays.append((surface, None))
        if name:
            cut = Slice(Input=source)
            cut.SliceType = 'Plane'
            bounds = source.GetDataInformation().GetBounds()
            cut.SliceType.Origin = [(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2,
                                    (bounds[4] + bounds[5]) / 2]
            cut.SliceType.Normal = [0.0, 0.0, 1.0]
            section = Show(cut, view)
            ColorBy(section, ('POINTS', name))
            displays.append((section, name))
        return displays
    display = Show(source, view)
    if role == 'samples':
        display.SetRepresentationType('Points')
        display.PointSize = 2
    elif role in ('network', 'collection'):
        display.SetRepresentationType('Surface')
        display.LineWidth = 3
    else:
        display.SetRepresentationType('Surface')
        if role == 'geology':
            display.Opacity = 0.35
    if not colour_by or colour_by not in arrays:
        colour_by = next((n for n in arrays if (spec_for(n, role) or {}).get('colouring') ==
                          'categorical'), None)
    if colour_by:
        ColorBy(display, (arrays[colour_by], colour_by))
    else:
        ColorBy(display, None)
        display.DiffuseColor = list(WALL)
    displays.append((display, colour_by))
    if role == 'samples' and colour_by == 'source':
        # The key points (source 0) are a handful among many samples: drawn larger, on top.
        keys = Threshold(Input=source, Scalars=['POINTS', 'source'])
        try:
            keys.LowerThreshold, keys.UpperThreshold = 0, 0
            keys.ThresholdMethod = 'Between'
        except AttributeError:  # ParaView before 5.10
            keys.ThresholdRange = [0, 0]
        key_display = Show(keys, view)
        key_display.SetRepresentationType('Points')
        key_display.PointSize = 9
        key_display.RenderPointsAsSpheres = 1
        ColorBy(key_display, ('POINTS', 'source'))
        displays.append((key_display, 'source'))
    return displays


def place_camera(view):
    """An oblique view from the south-south-east, 55 degrees above the horizon, z up (north
    leans away from the viewer)."""
    view.ResetCamera()
    camera = view.GetActiveCamera()
    fx, fy, fz = camera.GetFocalPoint()
    px, py, pz = camera.GetPosition()
    d = math.sqrt((px - fx) ** 2 + (py - fy) ** 2 + (pz - fz) ** 2)
    az, el = math.radians(20), math.radians(55)
    view.CameraFocalPoint = [fx, fy, fz]
    view.CameraPosition = [fx + d * math.sin(az) * math.cos(el),
                           fy - d * math.cos(az) * math.cos(el), fz + d * math.sin(el)]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()


def main(argv):
    opts = parse_options(argv)
    view = setup_view()
    if opts['screenshot']:  # text sizes are in pixels of the view: render at the image's size
        view.ViewSize = opts['size']
    sources, luts, legend = [], {}, {'karst': KARST_VERSION, 'files': [], 'arrays': {}}
    for item in FILES:
        path = os.path.join(HERE, item['file'])
        if not os.path.exists(path):
            print('karst: %s is missing; not shown' % path)
            continue
        source = OpenDataFile(path)
        source.UpdatePipeline()
        sources.append((item, source))
    ranges, names_of, units_of, role_of = {}, {}, {}, {}
    for item, source in sources:
        for assoc, name, (lo, hi) in arrays_of(source):
            a, b = ranges.get(name, (lo, hi))
            ranges[name] = (min(a, lo), max(b, hi))
            role_of.setdefault(name, item['role'])
            spec = spec_for(name, role_of[name])
            if spec and spec.get('names') and name not in names_of:
                names_of[name] = file_strings(source, spec['names'])
            if name not in units_of:
                units_of[name] = file_unit(source, name)
    shown_bars = []
    for item, source in sources:
        visible = item['role'] not in HIDDEN_AT_START if opts['show'] is None else \
            item['role'] in opts['show']
        for display, name in show_source(view, item, source):
            if not visible:
                Hide(display.Input, view)
            elif name and name not in shown_bars:
                shown_bars.append(name)
            legend['files'].append({'file': item['file'], 'role': item['role'],
                                    'colour_by': name, 'visible': visible})
    # One lookup table and one colour bar per array name, set up once every file is shown
    # (showing and colouring rescale tables), so that colouring by another array in
    # ParaView's GUI also finds its categories and its titled bar.
    for name, (lo, hi) in sorted(ranges.items()):
        spec = spec_for(name, role_of[name])
        if spec is None:  # not in karst's dictionary: titled with the unit the file states
            unit = units_of.get(name)
            spec = {'title': '%s (%s)' % (name, unit) if unit else name, 'colouring': 'sequential'}
        if spec['colouring'] == 'categorical' and 'categories' in spec:
            lut = categorical_lut(name, spec, names_of.get(name), lo, hi)
        else:
            lut = continuous_lut(name, spec['colouring'], lo, hi)
        style_bar(GetScalarBar(lut, view), spec['title'])
        luts[name] = lut
    for k, name in enumerate(shown_bars):
        bar = GetScalarBar(luts[name], view)
        bar.WindowLocation = CORNERS[k % len(CORNERS)]
        bar.Visibility = 1
    note = Text(Text='x east, y north, z up (m); karst %s' % KARST_VERSION)
    note_display = Show(note, view)
    note_display.Color = list(FOREGROUND)
    note_display.FontSize = 14
    note_display.WindowLocation = 'Upper Center'
    place_camera(view)
    Render(view)
    for name, lut in luts.items():
        bar = GetScalarBar(lut, view)
        legend['arrays'][name] = {
            'categorical': bool(lut.InterpretValuesAsCategories),
            'annotations': list(lut.Annotations), 'indexed_colors': list(lut.IndexedColors),
            'rgb_points': list(lut.RGBPoints), 'title': bar.Title,
            'bar_visible': bool(bar.Visibility),
            'names_from_file': names_of.get(name) is not None}
    if opts['legend']:
        with open(opts['legend'], 'w') as f:
            json.dump(legend, f, indent=1, sort_keys=True)
    if opts['screenshot']:
        SaveScreenshot(opts['screenshot'], view, ImageResolution=opts['size'],
                       TransparentBackground=0)
    return view


main(sys.argv[1:])
