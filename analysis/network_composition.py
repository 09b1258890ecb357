#!/usr/bin/python3
"""Length of a generated network by zone (vadose, epiphreatic, phreatic) and by tunnel type.

Usage: /usr/bin/python3 analysis/network_composition.py DIR/network.vtp [...]
Reads the .vtp with VTK (python3-vtk9) independently of karst and prints, per file, the total
length and the share of it in each zone and each tunnel type (names from the file's field data).
"""
import math
import sys

import vtk


def names(fd, key):
    a = fd.GetAbstractArray(key)
    return [a.GetValue(i) for i in range(a.GetNumberOfValues())] if a else []


def composition(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    pd = r.GetOutput()
    cd, fd = pd.GetCellData(), pd.GetFieldData()
    tt, zone = cd.GetArray("tunnel_type"), cd.GetArray("zone")
    tnames, znames = names(fd, "tunnel_type_names"), names(fd, "zone_names")
    by_type, by_zone, total = {}, {}, 0.0
    pts = pd.GetPoints()
    for c in range(pd.GetNumberOfCells()):
        ids = pd.GetCell(c).GetPointIds()
        a, b = pts.GetPoint(ids.GetId(0)), pts.GetPoint(ids.GetId(1))
        L = math.dist(a, b)
        total += L
        t = int(tt.GetValue(c))
        by_type[t] = by_type.get(t, 0.0) + L
        if zone is not None:
            z = int(zone.GetValue(c))
            by_zone[z] = by_zone.get(z, 0.0) + L
    return total, by_type, by_zone, tnames, znames


def main():
    for path in sys.argv[1:]:
        total, by_type, by_zone, tn, zn = composition(path)
        print(f"{path}: {total:.0f} m")
        print("  zones: " + ", ".join(f"{zn[z] if z < len(zn) else z} {100 * L / total:.0f} %"
                                      for z, L in sorted(by_zone.items())))
        print("  types: " + ", ".join(f"{tn[t] if t < len(tn) else t} {100 * L / total:.0f} %"
                                      for t, L in sorted(by_type.items())))


if __name__ == "__main__":
    main()
