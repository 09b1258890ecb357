#!/usr/bin/python3
"""Write terrain.asc for dowprov_extension.yaml: a coarse ground surface for the Dow Cave -
Providence Pot area in EPSG:7405 (British National Grid, ODN heights), built from the survey's own
surface stations (Survex SURFACE and ENTRANCE flags of datasets/surveys/dowprov/DowProv.3d, read
with Survex's dump3d). No elevation model is shipped with karst, so this is an interpolation, not
a DEM: a least-squares plane through the 28 surface stations (bounded to [Z_LOW, Z_HIGH]) plus an inverse-distance (power 2)
correction of its residuals, raised where needed so that every underground station lies at least
CLEARANCE m below the ground. Run from the repository root:

  /usr/bin/python3 datasets/scenarios/dowprov/make_terrain.py > datasets/scenarios/dowprov/terrain.asc
"""
import subprocess
import sys

SURVEY = "datasets/surveys/dowprov/DowProv.3d"
X0, Y0, NX, NY, CELL = 398200.0, 472750.0, 49, 69, 25.0  # cell centres, m
CLEARANCE = 3.0  # m of rock kept above every underground station
REACH = 1.5 * CELL  # an underground station raises the cells within this horizontal distance
# The plane's extrapolation to the corners of the grid is bounded by the floor of Wharfedale
# near Kettlewell (about 250 m) and the summit of Great Whernside (704 m).
Z_LOW, Z_HIGH = 250.0, 704.0

surface, underground = [], []
for line in subprocess.run(["dump3d", SURVEY], check=True, capture_output=True,
                           text=True).stdout.splitlines():
    t = line.split()
    if not t or t[0] != "NODE":
        continue
    p = (float(t[1]), float(t[2]), float(t[3]))
    if "SURFACE" in line or "ENTRANCE" in line:
        surface.append(p)
    if "UNDERGROUND" in line or "ENTRANCE" in line:
        underground.append(p)

# Least-squares plane z = a + b (x - xm) + c (y - ym) by the 3 x 3 normal equations.
xm = sum(p[0] for p in surface) / len(surface)
ym = sum(p[1] for p in surface) / len(surface)
rows = [(1.0, p[0] - xm, p[1] - ym, p[2]) for p in surface]
M = [[sum(r[i] * r[j] for r in rows) for j in range(3)] for i in range(3)]
v = [sum(r[i] * r[3] for r in rows) for i in range(3)]
for i in range(3):  # Gauss-Jordan
    piv = M[i][i]
    for j in range(3):
        M[i][j] /= piv
    v[i] /= piv
    for k in range(3):
        if k != i:
            f = M[k][i]
            for j in range(3):
                M[k][j] -= f * M[i][j]
            v[k] -= f * v[i]
a, b, c = v


def plane(x, y):
    return a + b * (x - xm) + c * (y - ym)


resid = [(p[0], p[1], p[2] - plane(p[0], p[1])) for p in surface]


def ground(x, y):
    num = den = 0.0
    for px, py, r in resid:
        d2 = (x - px) ** 2 + (y - py) ** 2
        if d2 < 1e-6:
            return plane(x, y) + r
        w = 1.0 / d2
        num += w * r
        den += w
    z = min(max(plane(x, y) + num / den, Z_LOW), Z_HIGH)
    for px, py, pz in underground:
        if (x - px) ** 2 + (y - py) ** 2 <= REACH * REACH:
            z = max(z, pz + CLEARANCE)
    return z


out = sys.stdout
out.write(f"ncols        {NX}\nnrows        {NY}\nxllcenter    {X0:.0f}\nyllcenter    {Y0:.0f}\n"
          f"cellsize     {CELL:.0f}\nNODATA_value -9999\n")
for j in range(NY - 1, -1, -1):  # ESRI grids list the northern row first
    out.write(" ".join(f"{ground(X0 + i * CELL, Y0 + j * CELL):.1f}" for i in range(NX)) + "\n")
