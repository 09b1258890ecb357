#!/usr/bin/python3
"""Check what Debian's ParaView made of a script karst wrote (tests/cli/test_paraview.sh).

    check_paraview.py SCRIPT LEGEND.json SCREENSHOT.png DATA.vtp ARRAY [--shaded | --legend-only]
                      [--role ROLE]

SCRIPT is the *.paraview.py karst wrote, LEGEND.json and SCREENSHOT.png what pvbatch saved
running it (--legend, --screenshot), DATA.vtp the file shown, ARRAY its categorical array
coloured at start; --shaded for lit surfaces (compared by hue), --legend-only for translucent
ones (checks 1, 3, 4 and the swatches); --role the kind of file when the array's name means
something else elsewhere (geology's "feature"). Independently of ParaView and of karst, the data file is read with VTK
(python3-vtk9) and the PNG decoded here (zlib and the PNG filters, ISO/IEC 15948 sect. 9):

1. ParaView's lookup table of ARRAY is categorical, its colour bar is visible and titled, its
   annotations are the category names of the file's "<ARRAY>_names" field data (read by the
   script from the file, not from its own table), and its colours are the palette the script
   carries (test_view checks that palette against include/karst/palette.h);
2. every category present in the data is drawn in its colour in the picture (outside the
   legend), no absent one is, a category covering most of the data covers most pixels, and
   every category of the legend has its swatch;
3. the legend holds text (dark pixels beside the swatches);
4. every continuous array has a colour bar titled with the unit the file states for it
   ("array_units"), on the palette's ramp, diverging ones symmetric about 0.
Prints one line per check and exits 1 on the first failure.
"""
import ast
import json
import re
import struct
import sys
import zlib

from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

#: A pixel "has" a colour when each channel is within this of it (VTK writes exact 8-bit
#: colours for unlit lines, points and legend swatches; antialiased edges blend with white).
CHANNEL_TOLERANCE = 12
#: Pixels of a category's colour in the data area that show it was drawn (a few pixels of a
#: 3-pixel line: the shortest conduits are a metre long); fewer mean it was not drawn. The
#: legend's swatches are far larger (about 15 x 40).
MIN_DATA_PIXELS = 4
#: Lit surfaces: a pixel has a colour's hue when, both scaled to a maximum channel of 1, each
#: channel is within this (diffuse shading scales r, g and b alike); darker pixels are ignored.
HUE_TOLERANCE = 0.08
MIN_SHADED_VALUE = 30
MIN_SWATCH_PIXELS = 150
#: The legend sits in the lower right corner: the right LEGEND_FRACTION of the picture; the
#: note "x east, y north ..." in the top NOTE_FRACTION, the orientation axes in the lower left
#: AXES_FRACTION square.
LEGEND_FRACTION = 0.17
NOTE_FRACTION = 0.05
AXES_FRACTION = 0.2
#: Lit surfaces: an absent category may match this fraction of the most drawn one's pixels.
STRAY_FRACTION = 0.02


def fail(msg):
    print('FAIL: ' + msg)
    sys.exit(1)


def ok(msg):
    print('ok: ' + msg)


def read_png(path):
    """(width, height, rows of (r, g, b) tuples) of an 8-bit RGB or RGBA PNG."""
    data = open(path, 'rb').read()
    if data[:8] != b'\x89PNG\r\n\x1a\n':
        fail('%s is not a PNG file' % path)
    pos, idat, hdr = 8, b'', None
    while pos < len(data):
        (n,) = struct.unpack('>I', data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b'IHDR':
            hdr = struct.unpack('>IIBBBBB', body)
        elif kind == b'IDAT':
            idat += body
    w, h, depth, ctype, _, _, interlace = hdr
    if depth != 8 or ctype not in (2, 6) or interlace:
        fail('%s: only 8-bit RGB/RGBA non-interlaced PNG is read here' % path)
    bpp = 3 if ctype == 2 else 4
    raw, stride = zlib.decompress(idat), w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else b if pb <= pc else c
                line[i] = (line[i] + pr) & 255
        rows.append([tuple(line[i:i + 3]) for i in range(0, stride, bpp)])
        prev = line
    return w, h, rows


def script_data(path):
    """The data part of a karst ParaView script (FILES, ARRAYS, RAMPS ...), evaluated."""
    text = open(path, encoding='utf-8').read()
    head = text.split('# ----------', 1)[0]
    env = {}
    exec(compile(head, path, 'exec'), env)  # only literals and os.fsdecode
    return env


def read_vtp(path):
    r = vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def strings(fd, name):
    a = fd.GetAbstractArray(name)
    return None if a is None else [a.GetValue(i) for i in range(a.GetNumberOfValues())]


def units_of(fd):
    t = fd.GetAbstractArray('array_units')
    if t is None:
        return {}
    return {t.GetValue(3 * i): t.GetValue(3 * i + 1) for i in range(t.GetNumberOfTuples())}


def to8(rgb):
    return tuple(int(round(255 * c)) for c in rgb)


def near(p, q):
    return all(abs(a - b) <= CHANNEL_TOLERANCE for a, b in zip(p, q))


def stray_limit(shaded, drawn):
    """Pixels of an absent category's colour that still mean "not drawn": none in an unlit
    picture; in a lit one, specular highlights shift hues, STRAY_FRACTION of the most drawn."""
    if not shaded:
        return MIN_DATA_PIXELS
    return max(MIN_DATA_PIXELS, STRAY_FRACTION * max(drawn.values(), default=0))


def same_hue(p, q):
    if max(p) < MIN_SHADED_VALUE:
        return False
    mp, mq = max(p), max(q)
    return all(abs(a / mp - b / mq) <= HUE_TOLERANCE for a, b in zip(p, q))


def weight(data, values, i):
    """What item i of a categorical array covers: a line's length, a triangle's area, 1 for a
    point (shares of the picture)."""
    if values.GetNumberOfTuples() != data.GetNumberOfCells() or data.GetNumberOfCells() == 0:
        return 1.0
    cell = data.GetCell(i)
    pts = [data.GetPoint(cell.GetPointId(k)) for k in range(cell.GetNumberOfPoints())]
    if len(pts) == 2:
        return sum((a - b) ** 2 for a, b in zip(*pts)) ** 0.5
    if len(pts) == 3:
        u = [b - a for a, b in zip(pts[0], pts[1])]
        v = [b - a for a, b in zip(pts[0], pts[2])]
        c = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        return 0.5 * sum(x * x for x in c) ** 0.5
    return 1.0


def main():
    script, legend_path, png, data_path, array = sys.argv[1:6]
    flags = sys.argv[6:]
    shaded, legend_only = '--shaded' in flags, '--legend-only' in flags
    role = flags[flags.index('--role') + 1] if '--role' in flags else None

    env = script_data(script)
    legend = json.load(open(legend_path))
    data = read_vtp(data_path)
    fd = data.GetFieldData()
    spec = env['ROLE_ARRAYS'].get(role, {}).get(array) or env['ARRAYS'][array]
    lut = legend['arrays'].get(array)
    if lut is None:
        fail('%s: no lookup table for %s' % (legend_path, array))

    # 1. categories, names from the file, palette colours
    names = strings(fd, spec['names'])
    if not names:
        fail('%s has no %s field data' % (data_path, spec['names']))
    if not (lut['categorical'] and lut['bar_visible'] and lut['names_from_file']):
        fail('%s: categorical %s, bar visible %s, names read from the file %s' %
             (array, lut['categorical'], lut['bar_visible'], lut['names_from_file']))
    if lut['title'] != spec['title']:
        fail('%s: colour bar titled %r, expected %r' % (array, lut['title'], spec['title']))
    ann = lut['annotations']
    got = {int(ann[i]): ann[i + 1] for i in range(0, len(ann), 2)}
    for code, label in enumerate(names):
        if got.get(code) != label:
            fail('%s: category %d is annotated %r, the file names it %r' %
                 (array, code, got.get(code), label))
    palette = {code: to8(rgb) for code, _, rgb in spec['categories']}
    colours = lut['indexed_colors']
    lut_rgb = {int(ann[2 * k]): to8(colours[3 * k:3 * k + 3]) for k in range(len(ann) // 2)}
    for code, rgb in lut_rgb.items():
        expected = palette.get(code) or to8(env['CYCLE'][code % len(env['CYCLE'])])
        if expected != rgb:
            fail('%s: category %d has colour %s in ParaView, %s in the palette' %
                 (array, code, rgb, expected))
    ok('%s: %d categories annotated with the file\'s names (%s) in the palette\'s colours' %
       (array, len(names), ', '.join(names)))

    # 2. categories present in the data are drawn in their colours (lit surfaces: in their
    #    chromaticity), absent ones are not; the most common one dominates; swatches in the
    #    legend
    values = data.GetCellData().GetArray(array) or data.GetPointData().GetArray(array)
    share = {}
    for i in range(values.GetNumberOfTuples()):
        code = int(values.GetValue(i))
        share[code] = share.get(code, 0) + weight(data, values, i)
    present = sorted(share)
    w, h, rows = read_png(png)
    x_legend = int(w * (1 - LEGEND_FRACTION))
    # The data area: left of the legend, below the note at the top, outside the orientation
    # axes in the lower left corner (text and axes labels are black, like chambers).
    x_axes, y_axes = int(w * AXES_FRACTION), h * (1 - AXES_FRACTION)
    area = [row[x_axes:x_legend] if y > y_axes else row[:x_legend]
            for y, row in enumerate(rows) if y > h * NOTE_FRACTION]
    drawn = {}
    for code in sorted(lut_rgb):
        rgb = lut_rgb[code]
        label = got[code]
        chromatic = max(rgb) - min(rgb) > 60
        if legend_only:
            pass
        elif shaded and not chromatic:
            print('   %-16s not checked in the shaded picture (no hue)' % label)
        else:
            match = (lambda p: same_hue(p, rgb)) if shaded else (lambda p: near(p, rgb))
            drawn[code] = sum(match(p) for row in area for p in row)
            if code in present and drawn[code] < MIN_DATA_PIXELS:
                fail('%s %r is in the data but only %d pixels of its colour %s are drawn' %
                     (array, label, drawn[code], rgb))
            if code not in present and drawn[code] >= stray_limit(shaded, drawn):
                fail('%s %r is not in the data but %d pixels have its colour %s' %
                     (array, label, drawn[code], rgb))
        in_legend = sum(near(p, rgb) for row in rows for p in row[x_legend:])
        if in_legend < MIN_SWATCH_PIXELS:
            fail('%s %r: its legend swatch has %d pixels of %s' % (array, label, in_legend, rgb))
        print('   %-16s %s: %6s pixels in the picture, %5d in the legend%s' %
              (label, '#%02X%02X%02X' % rgb, drawn.get(code, '-'), in_legend,
               '' if code in present else ' (not in the data)'))
    # Absent categories were checked against the pixels counted so far; check again with all.
    for code in drawn:
        if code not in present and drawn[code] >= stray_limit(shaded, drawn):
            fail('%s %r is not in the data but %d pixels have its colour' %
                 (array, got[code], drawn[code]))
    top = max(share, key=share.get) if share else None
    if top is not None and share[top] > 0.5 * sum(share.values()) and top in drawn and \
            drawn[top] < max(drawn.values()):
        fail('%s %r makes %.0f %% of the data but is not the most drawn colour' %
             (array, got.get(top), 100 * share[top] / sum(share.values())))
    if legend_only:
        ok('%d swatches in the legend (the picture not measured: translucent surfaces)' %
           len(lut_rgb))
    else:
        ok('%d categories present in the data drawn in their colours, the others not; %d swatches'
           % (len(present), len(lut_rgb)))

    # 3. the legend has text: dark grey-to-black pixels that are not a swatch colour
    swatches = list(lut_rgb.values())
    text = sum(1 for row in rows for p in row[x_legend:]
               if max(p) < 110 and max(p) - min(p) < 30 and not any(near(p, s) for s in swatches))
    if text < 200:
        fail('the legend has %d text pixels; its names are missing' % text)
    ok('legend text present (%d dark pixels beside the swatches)' % text)

    # 4. continuous arrays: titled with the file's unit, on the palette's ramp
    file_units = units_of(fd)
    for name, l in sorted(legend['arrays'].items()):
        if l['categorical']:
            continue
        s = env['ARRAYS'].get(name)
        unit = file_units.get(name)
        if s is None or unit is None:
            continue
        shown = 'dimensionless' if unit == '1' else unit
        paren = re.search(r'\(([^)]*)\)', l['title'])
        if not paren or not re.search(r'(^|[\s,])' + re.escape(shown) + r'($|[\s,])',
                                      paren.group(1)):
            fail('%s: colour bar title %r does not give the unit %r the file states' %
                 (name, l['title'], unit))
        pts = l['rgb_points']
        ramp = env['RAMPS'][s['colouring']]
        if [round(c, 4) for c in pts[1:4]] != [round(c, 4) for c in ramp[0][1:4]] or \
                [round(c, 4) for c in pts[-3:]] != [round(c, 4) for c in ramp[-1][1:4]]:
            fail('%s: ParaView\'s colour map is not the palette\'s %s ramp' % (name, s['colouring']))
        if s['colouring'] == 'diverging' and abs(pts[0] + pts[-4]) > 1e-9 * max(1, abs(pts[0])):
            fail('%s: diverging map over [%g, %g], not symmetric about 0' % (name, pts[0], pts[-4]))
        print('   %-20s %r on the %s ramp over [%.4g, %.4g]' %
              (name, l['title'], s['colouring'], pts[0], pts[-4]))
    ok('continuous arrays titled with their units')


if __name__ == '__main__':
    main()
