#!/usr/bin/env bash
# Every output names the versions of the libraries karst uses, and all name the same ones:
# `karst --version`, run.json and ensemble.json ("versions"), the field data "versions" of
# network.vtp, samples.vtp, geology.vtp and a mesh .vtp, a .ply mesh's header comments, the GeoPackage's
# metadata, and the report's software section. The versions themselves are
# checked against independent sources: pkg-config, gdal-config, dpkg, mpirun, and VTK's own
# vtkVersion through Debian's python3-vtk9.
set -u
KARST=$1
SRC=$2
PY=/usr/bin/python3
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$KARST" --version >"$T/version.txt" || fail "karst --version"
cat "$T/version.txt"
ver() { awk -v n="$1" '$1 == n { $1 = ""; sub(/^ /, ""); print }' "$T/version.txt"; }
want() { # name expected
  [ "$(ver "$1")" = "$2" ] || fail "--version says $1 '$(ver "$1")', expected '$2'"
  echo "ok: $1 $2"
}
want karst "$(sed -n 's/^project(karst VERSION \([0-9.]*\).*/\1/p' "$SRC/CMakeLists.txt")"
want libyaml "$(pkg-config --modversion yaml-0.1)"
want GeographicLib "$(pkg-config --modversion geographiclib)"
want FLANN "$(pkg-config --modversion flann)"
want GDAL "$(gdal-config --version)"
want PROJ "$(pkg-config --modversion proj)"
want CGAL "$(dpkg-query -W -f='${Version}' libcgal-dev | sed 's/-.*//')"
want VTK "$("$PY" -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion())')"
case "$(ver MPI)" in
"Open MPI "*) want MPI "Open MPI $(mpirun --version | sed -n 's/^mpirun (Open MPI) //p' | head -n 1) (MPI 3.1)" ;;
"not built with MPI") echo "ok: MPI not built" ;;
*) fail "MPI line '$(ver MPI)'" ;;
esac
ver compiler | grep -q "^GCC \|^clang " || fail "compiler line"

# The outputs: one realisation with its samples, a two-member ensemble and its report.
"$KARST" generate "$SRC/datasets/scenarios/branchwork.yaml" -o "$T/gen" --samples -q || fail "generate"
"$KARST" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 2 -j 1 -o "$T/ens" -q || fail "ensemble"
"$KARST" report "$T/ens" -o "$T/report.html" || fail "report"
"$KARST" mesh "$SRC/datasets/surveys/karstnet/g_huttes.sql" -o "$T/cave.ply" --voxel 1 -q || fail "mesh ply"
"$KARST" mesh "$SRC/datasets/surveys/karstnet/g_huttes.sql" -o "$T/cave.vtp" --voxel 1 -q || fail "mesh vtp"
"$KARST" export "$T/gen" --gpkg "$T/gen.gpkg" -q || fail "export"
"$PY" - "$T" <<'PY' || fail "versions in the outputs"
import html, json, sys
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

T = sys.argv[1]
lines = [l.rstrip("\n") for l in open(f"{T}/version.txt")]
want = dict(l.split(" ", 1) for l in lines)
bad = []
for f in ("gen/run.json", "ens/ensemble.json"):
    got = json.load(open(f"{T}/{f}"))["versions"]
    if got != want or list(got) != list(want):
        bad.append(f"{f}: {got} != {want}")
for f in ("gen/network.vtp", "gen/samples.vtp", "gen/geology.vtp", "ens/realisations/0000/network.vtp",
          "cave.vtp"):
    r = vtkXMLPolyDataReader()
    r.SetFileName(f"{T}/{f}")
    r.Update()
    a = r.GetOutput().GetFieldData().GetAbstractArray("versions")
    got = [a.GetValue(i) for i in range(a.GetNumberOfValues())] if a else None
    if got != lines:
        bad.append(f"{f}: field data versions {got} != {lines}")
head = open(f"{T}/cave.ply", "rb").read(4096).split(b"end_header")[0].decode()
got = [l[len("comment "):] for l in head.splitlines() if l.startswith("comment ")]
if got != lines:
    bad.append(f"cave.ply: header comments {got} != {lines}")
page = html.unescape(open(f"{T}/report.html").read())
if "\n".join(lines) not in page:
    bad.append("report.html: the software section is not the --version list")
for b in bad:
    print("FAIL:", b)
print("ok: run.json, ensemble.json, network.vtp, samples.vtp, geology.vtp, the mesh .vtp and .ply and the "
      "report name", len(lines), "components")
sys.exit(1 if bad else 0)
PY
# The GeoPackage's dataset metadata (GDAL's own ogrinfo reads it).
ogrinfo -ro -so "$T/gen.gpkg" conduits >"$T/gpkg.txt" || fail "ogrinfo"
"$PY" - "$T" <<'PY' || fail "versions in the GeoPackage"
import json, sys
T = sys.argv[1]
want = dict(l.rstrip("\n").split(" ", 1) for l in open(f"{T}/version.txt"))
meta = [l.strip() for l in open(f"{T}/gpkg.txt") if l.startswith("  versions=")]
got = json.loads(meta[0][len("versions="):]) if meta else None
if got != want:
    print("FAIL: GeoPackage metadata versions", got)
    sys.exit(1)
print("ok: the GeoPackage's metadata name the same", len(want), "components")
PY
echo "ok: versions"
