#!/usr/bin/python3
"""Write the three surfaces of the `plateau` scenario, reproducibly.

    /usr/bin/python3 datasets/scenarios/plateau/make_surfaces.py [OUTDIR]

(OUTDIR defaults to this script's folder.) Only the standard library is used and
nothing is random, so the files are the same byte for byte on every run.

fold_horizon.ts: a folded inception horizon, an anticline whose axis runs N-S near
  x = 1000 m (curving by +-40 m), crest at 250 m, limbs dipping towards 8 degrees
  east and west. The profile across the axis is a hyperbola, smooth at the crest:

      z(x, y) = 250 - tan(8 deg) * (sqrt(d^2 + w^2) - w),   d = x - a(y),
      a(y) = 1000 + 40 sin(2 pi y / 3000),                    w = 150 m,

  so the dip is 0 on the axis and tends to 8 degrees on the limbs (7.2 degrees at
  d = 500 m, 7.8 at d = 1000 m). It is written as a geomodeller writes a TSurf:
  HEADER and coordinate-system blocks, a vertex property (the local dip, degrees),
  two TFACE parts (the west and the east limb) sharing the column of vertices
  nearest the axis, which the second part repeats as ATOMs, BSTONE and BORDER
  lines, END. The mesh covers x in [-50, 2050], y in [-50, 1550] (the domain
  0..2000 x 0..1500 m with a 50 m margin): columns 20 m apart within 200 m of
  x = 1000 and 50 m apart beyond, rows 40 m apart, each cell cut along alternating
  diagonals: 2 x 54 x 40 = 4320 triangles.

water_table.asc: an ESRI ASCII grid of the water table, 20 m cells centred on
  x = 0, 20, ..., 2000 and y = 0, 20, ..., 1500 (101 x 76 nodes), dipping gently
  to the south-east:

      z = 150 + 70 (1 - s)^1.2 + 2 sin(2 pi x / 1000) sin(2 pi y / 900),
      s = (x + 1500 - y) / 3500   (0 at the north-west corner, 1 at the south-east),

  from 220 m in the north-west to 150 m in the south-east, rounded to 1 cm.

terrain.asc: the plateau's ground, an ESRI ASCII grid of 25 m cells centred on
  x = 0, 25, ..., 2000 and y = 0, 25, ..., 1500 (81 x 61 nodes): a gently undulating
  surface around 370 m with ten dolines (closed depressions, Gaussian, 6-9 m deep,
  35 m across) where the scenario's sinks are,

      z = 370 + 10 sin(2 pi x / 1700) cos(2 pi y / 1300) + 6 sin(2 pi (x + y) / 900)
          - sum_k d_k exp(-|p - c_k|^2 / (2 * 35^2)),

  rounded to 1 cm (DOLINES lists c_k and d_k).
"""
import math
import os
import sys

TAN8 = math.tan(math.radians(8.0))
W = 150.0


def axis_x(y):
    return 1000.0 + 40.0 * math.sin(2.0 * math.pi * y / 3000.0)


def fold_z(x, y):
    d = x - axis_x(y)
    return 250.0 - TAN8 * (math.sqrt(d * d + W * W) - W)


def fold_dip_deg(x, y):
    # |grad z|: dz/dd = -tan8 d / sqrt(d^2 + w^2); the axis' curvature adds a'(y) dz/dd in y.
    d = x - axis_x(y)
    dzdd = -TAN8 * d / math.sqrt(d * d + W * W)
    da = 40.0 * 2.0 * math.pi / 3000.0 * math.cos(2.0 * math.pi * y / 3000.0)
    return math.degrees(math.atan(math.hypot(dzdd, -dzdd * da)))


def columns():
    xs = [-50.0 + 50.0 * i for i in range(0, 18)]  # -50 .. 800
    xs += [800.0 + 20.0 * i for i in range(1, 20)]  # 820 .. 1180
    xs += [1200.0 + 50.0 * i for i in range(0, 18)]  # 1200 .. 2050
    return xs


def write_fold(path):
    xs = columns()
    ys = [-50.0 + 40.0 * j for j in range(0, 41)]  # -50 .. 1550
    split = xs.index(1000.0)  # the shared column
    lines = [
        "GOCAD TSurf 1",
        "HEADER {",
        "name:H1_inception_anticline",
        "*solid*color:0.85 0.55 0.25 1",
        "ivolmap:false",
        "imap:false",
        "mesh:on",
        "}",
        "GOCAD_ORIGINAL_COORDINATE_SYSTEM",
        'NAME "plateau local"',
        'AXIS_NAME "X" "Y" "Z"',
        'AXIS_UNIT "m" "m" "m"',
        "ZPOSITIVE Elevation",
        "END_ORIGINAL_COORDINATE_SYSTEM",
        "GEOLOGICAL_FEATURE H1_inception",
        "GEOLOGICAL_TYPE top",
        "STRATIGRAPHIC_POSITION H1 1",
        "PROPERTIES dip",
        "PROP_LEGAL_RANGES **none** **none**",
        "NO_DATA_VALUES -99999",
        "PROPERTY_CLASSES dip",
        "PROPERTY_KINDS Dip",
        "PROPERTY_SUBCLASSES QUANTITY Float",
        "ESIZES 1",
        "UNITS deg",
        "PROPERTY_CLASS_HEADER dip {",
        "kind:Dip",
        "unit:deg",
        "low_clip:0",
        "high_clip:8",
        "}",
    ]
    ids = {}
    next_id = [1]

    def vertex(i, j):
        x, y = xs[i], ys[j]
        vid = next_id[0]
        next_id[0] += 1
        lines.append("PVRTX %d %.3f %.3f %.4f %.3f" % (vid, x, y, fold_z(x, y), fold_dip_deg(x, y)))
        return vid

    parts = [(0, split), (split, len(xs) - 1)]
    for p, (i0, i1) in enumerate(parts):
        lines.append("TFACE")
        local = {}
        for j in range(len(ys)):
            for i in range(i0, i1 + 1):
                if p == 1 and i == i0:  # the shared column: the same points, new ids
                    aid = next_id[0]
                    next_id[0] += 1
                    lines.append("ATOM %d %d" % (aid, ids[(i, j)]))
                    local[(i, j)] = aid
                else:
                    local[(i, j)] = ids[(i, j)] = vertex(i, j)
        for j in range(len(ys) - 1):
            for i in range(i0, i1):
                a, b = local[(i, j)], local[(i + 1, j)]
                c, d = local[(i, j + 1)], local[(i + 1, j + 1)]
                if (i + j) % 2 == 0:
                    lines.append("TRGL %d %d %d" % (a, b, d))
                    lines.append("TRGL %d %d %d" % (a, d, c))
                else:
                    lines.append("TRGL %d %d %d" % (a, b, c))
                    lines.append("TRGL %d %d %d" % (b, d, c))
        corners = [local[(i0, 0)], local[(i1, 0)], local[(i1, len(ys) - 1)], local[(i0, len(ys) - 1)]]
        for c in corners:
            lines.append("BSTONE %d" % c)
        border_id = next_id[0]
        next_id[0] += 1
        lines.append("BORDER %d %d %d" % (border_id, corners[0], local[(i0 + 1, 0)]))
    lines.append("END")
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
    return 2 * sum(i1 - i0 for i0, i1 in parts) * (len(ys) - 1)


def water_z(x, y):
    s = (x + 1500.0 - y) / 3500.0
    return (150.0 + 70.0 * (1.0 - s) ** 1.2
            + 2.0 * math.sin(2.0 * math.pi * x / 1000.0) * math.sin(2.0 * math.pi * y / 900.0))


def write_water_table(path):
    ncols, nrows, cs = 101, 76, 20.0
    out = [
        "ncols        %d" % ncols,
        "nrows        %d" % nrows,
        "xllcorner    -10",
        "yllcorner    -10",
        "cellsize     20",
        "NODATA_value -9999",
    ]
    for r in range(nrows):  # north to south
        y = (nrows - 1 - r) * cs
        out.append(" ".join("%.2f" % water_z(c * cs, y) for c in range(ncols)))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(out) + "\n")


# Doline centres (x, y) and depths (m): the sinks of plateau.yaml sit at their bottoms.
DOLINES = [(250, 300, 8), (420, 1150, 7), (640, 700, 9), (900, 1300, 6), (1120, 250, 8),
           (1300, 900, 7), (1500, 1350, 8), (1650, 500, 9), (1820, 1050, 6), (760, 200, 7)]


def terrain_z(x, y):
    z = (370.0 + 10.0 * math.sin(2 * math.pi * x / 1700.0) * math.cos(2 * math.pi * y / 1300.0)
         + 6.0 * math.sin(2 * math.pi * (x + y) / 900.0))
    for cx, cy, d in DOLINES:
        z -= d * math.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * 35.0 ** 2))
    return z


def write_terrain(path):
    ncols, nrows, cs = 81, 61, 25.0
    out = [
        "ncols        %d" % ncols,
        "nrows        %d" % nrows,
        "xllcorner    -12.5",
        "yllcorner    -12.5",
        "cellsize     25",
        "NODATA_value -9999",
    ]
    for r in range(nrows):  # north to south
        y = (nrows - 1 - r) * cs
        out.append(" ".join("%.2f" % terrain_z(c * cs, y) for c in range(ncols)))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(out) + "\n")


def main():
    outdir = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    nt = write_fold(os.path.join(outdir, "fold_horizon.ts"))
    write_water_table(os.path.join(outdir, "water_table.asc"))
    write_terrain(os.path.join(outdir, "terrain.asc"))
    print("wrote %s (%d triangles), %s and %s" % (os.path.join(outdir, "fold_horizon.ts"), nt,
                                                 os.path.join(outdir, "water_table.asc"),
                                                 os.path.join(outdir, "terrain.asc")))


if __name__ == "__main__":
    main()
