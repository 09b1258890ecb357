#!/usr/bin/env bash
# karst export --gpkg: GDAL's own ogrinfo and ogr2ogr (Debian's gdal-bin) read the GeoPackage
# back. Expected values come from the inputs, read independently: feature counts from run.json,
# every attribute of every edge and node from network.vtp through python3-vtk9, key points from
# run.json; the coordinate system undefined (GeoPackage srs_id -1) without one, EPSG:2154 from a
# hand-edited run.json, EPSG:7405 from the Dow-Providence survey's own CS, and --crs overriding
# both; the .qml equal to the style QGIS finds in layer_styles, with one category per tunnel
# type; every attribute's unit and meaning in gpkg_data_columns as in network.vtp's array_units.
# Bad input: a clear message, exit 1, and no new or half-written file.
set -u
KARST=$1
SRC=$2
PY=/usr/bin/python3
T=$(mktemp -d)
trap 'chmod -R u+w "$T"; rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
unset SOURCE_DATE_EPOCH # section 4b sets it where it means to
command -v ogrinfo >/dev/null || fail "ogrinfo is required (scripts/install-deps installs gdal-bin)"

"$KARST" generate "$SRC/datasets/scenarios/branchwork.yaml" -o "$T/gen" -q || fail "generate"

# 1. No coordinate system in run.json: undefined.
"$KARST" export "$T/gen" --gpkg "$T/gen.gpkg" >"$T/out.txt" || { cat "$T/out.txt"; fail "export"; }
grep -q "coordinate system undefined" "$T/out.txt" || fail "summary names the undefined CRS: $(cat "$T/out.txt")"
[ -s "$T/gen.qml" ] || fail "no gen.qml beside gen.gpkg"
ls -a "$T" | grep -q "tmp" && fail "a temporary file was left: $(ls -a "$T")"
ogrinfo -ro -so "$T/gen.gpkg" conduits >"$T/conduits.txt" || fail "ogrinfo conduits"
ogrinfo -ro -so "$T/gen.gpkg" nodes >"$T/nodes.txt" || fail "ogrinfo nodes"
ogrinfo -ro -so "$T/gen.gpkg" key_points >"$T/kp.txt" || fail "ogrinfo key_points"
grep -q "^Geometry: 3D Line String" "$T/conduits.txt" || fail "conduits are not 3-D LineStrings"
grep -q "^Geometry: 3D Point" "$T/nodes.txt" || fail "nodes are not 3-D points"
grep -q "^Geometry: 3D Point" "$T/kp.txt" || fail "key points are not 3-D points"
for f in conduits nodes kp; do
  grep -q 'ENGCRS\["Undefined Cartesian SRS"' "$T/$f.txt" || fail "$f: CRS is not the undefined Cartesian one"
done
ogrinfo -ro -q "$T/gen.gpkg" -sql "SELECT srs_id FROM gpkg_geometry_columns WHERE srs_id <> -1" \
  | grep -q "srs_id" && fail "a layer has an srs_id other than -1 (undefined Cartesian)"
echo "ok: without a crs the layers are in the undefined Cartesian SRS (srs_id -1)"

# Counts and every attribute value against run.json and network.vtp.
for layer in conduits nodes key_points; do
  ogr2ogr -f CSV "$T/$layer.csv" "$T/gen.gpkg" "$layer" -lco GEOMETRY=AS_WKT || fail "ogr2ogr $layer"
done
ogrinfo -ro -q "$T/gen.gpkg" -sql "SELECT f_table_name, styleQML FROM layer_styles WHERE useAsDefault = 1" \
  >"$T/styles.txt" || fail "ogrinfo layer_styles"
ogr2ogr -f CSV "$T/columns.csv" "$T/gen.gpkg" -sql "SELECT * FROM gpkg_data_columns" \
  || fail "ogr2ogr gpkg_data_columns"
"$PY" - "$T" "$T/gen" <<'PY' || fail "GeoPackage contents differ from network.vtp and run.json"
import csv, json, math, sys
import xml.etree.ElementTree as ET
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

T, D = sys.argv[1], sys.argv[2]
bad = []
run = json.load(open(f"{D}/run.json"))
r = vtkXMLPolyDataReader()
r.SetFileName(f"{D}/network.vtp")
r.Update()
pd = r.GetOutput()
csv.field_size_limit(1 << 30)
rows = {l: list(csv.DictReader(open(f"{T}/{l}.csv"))) for l in ("conduits", "nodes", "key_points")}
n_edges, n_nodes = run["counts"]["network_edges"], run["counts"]["network_nodes"]
if len(rows["conduits"]) != n_edges: bad.append(f"{len(rows['conduits'])} conduits, run.json {n_edges}")
if len(rows["nodes"]) != n_nodes: bad.append(f"{len(rows['nodes'])} nodes, run.json {n_nodes}")
kps = run["parameters"]["key_points"]
if len(rows["key_points"]) != len(kps): bad.append(f"{len(rows['key_points'])} key points, run.json {len(kps)}")

def close(a, b):  # ogr2ogr writes reals with 15 significant digits
    return abs(a - b) <= 1e-13 * max(1.0, abs(b))

def wkt_points(w):
    inner = w[w.index("(") + 1:w.rindex(")")]
    return [tuple(map(float, p.split())) for p in inner.split(",")]

names = ["tube", "keyhole", "canyon", "bed", "passage", "epikarst", "chamber"]
cd, ptd = pd.GetCellData(), pd.GetPointData()
for label, data, n, rows_ in (("edge", cd, n_edges, rows["conduits"]), ("node", ptd, n_nodes, rows["nodes"])):
    arrays = [data.GetAbstractArray(i) for i in range(data.GetNumberOfArrays())]
    for a in arrays:
        if a.GetName() not in rows_[0]:
            bad.append(f"{label} attribute {a.GetName()} missing from the layer")
    for i, row in enumerate(rows_):
        if int(row[label]) != i:
            bad.append(f"{label} {i}: feature in position {i} is {row[label]}"); break
        for a in arrays:
            v, got = a.GetValue(i), row[a.GetName()]
            if isinstance(v, str):
                if got != v: bad.append(f"{label} {i}: {a.GetName()} '{got}' != '{v}'"); break
            elif not close(float(got), v):
                bad.append(f"{label} {i}: {a.GetName()} {got} != {v}"); break
        if label == "edge":
            t = int(row["tunnel_type"])
            if row["tunnel_type_name"] != names[t]: bad.append(f"edge {i}: tunnel_type_name {row['tunnel_type_name']}")
            pts = wkt_points(row["WKT"])
            cell = pd.GetCell(i)
            want = [pd.GetPoint(cell.GetPointId(k)) for k in range(2)]
            if len(pts) != 2 or any(not close(p, q) for a_, b_ in zip(pts, want) for p, q in zip(a_, b_)):
                bad.append(f"edge {i}: geometry {pts} != {want}")
            if int(row["from_node"]) != cell.GetPointId(0) or int(row["to_node"]) != cell.GetPointId(1):
                bad.append(f"edge {i}: ends {row['from_node']}-{row['to_node']}")
            if not close(float(row["length"]), math.dist(*want)): bad.append(f"edge {i}: length {row['length']}")
        else:
            p = wkt_points(row["WKT"])[0]
            if any(not close(a_, b_) for a_, b_ in zip(p, pd.GetPoint(i))): bad.append(f"node {i}: geometry")
        if len(bad) > 5: break
kind_names = ["interior", "sink", "spring", "waypoint", "junction", "amplification"]
kind = ptd.GetArray("kind")
for row, kp in zip(rows["key_points"], kps):
    p = wkt_points(row["WKT"])[0]
    if row["name"] != kp["name"] or row["type"] != kp["type"] or list(p) != kp["position"]:
        bad.append(f"key point {row['name']} {row['type']} {p} != {kp}")
    node = int(row["node"])
    if list(pd.GetPoint(node)) != kp["position"] or kind_names[int(kind.GetValue(node))] != kp["type"]:
        bad.append(f"key point {kp['name']}: node {node} is not the {kp['type']} at {kp['position']}")
    if row["kind_name"] != kp["type"]: bad.append(f"key point {kp['name']}: kind_name {row['kind_name']}")

# The .qml beside the GeoPackage is the conduits' style QGIS finds in layer_styles.
qml = open(f"{T}/gen.qml").read()
styles = open(f"{T}/styles.txt").read()
if qml.strip().splitlines()[2] not in styles: bad.append("gen.qml is not the conduits' layer_styles row")
for layer in ("conduits", "nodes", "key_points"):
    if f"f_table_name (String) = {layer}" not in styles: bad.append(f"no default style for {layer}")
root = ET.fromstring(qml.split("\n", 1)[1])
rend = root.find("renderer-v2")
if rend.get("type") != "categorizedSymbol" or rend.get("attr") != "tunnel_type": bad.append("renderer")
cats = {int(c.get("value")): c.get("label") for c in rend.iter("category")}
for t, nm in enumerate(names):
    if cats.get(t) != nm: bad.append(f"category {t} is {cats.get(t)}, expected {nm}")
colours = [s.find("layer/prop[@k='line_color']").get("v") for s in rend.iter("symbol")]
if len(set(colours)) != len(colours): bad.append(f"tunnel types share colours: {colours}")
# Every attribute's unit and meaning: gpkg_data_columns says what network.vtp's "array_units"
# table says (both from include/karst/arrays.h; read here through GDAL and VTK independently).
units = pd.GetFieldData().GetAbstractArray("array_units")
meaning = {units.GetValue(3 * i): (units.GetValue(3 * i + 1), units.GetValue(3 * i + 2))
           for i in range(units.GetNumberOfTuples())}
cols = {(r["table_name"], r["column_name"]): r for r in csv.DictReader(open(f"{T}/columns.csv"))}
for layer, data in (("conduits", cd), ("nodes", ptd)):
    for i in range(data.GetNumberOfArrays()):
        name = data.GetAbstractArray(i).GetName()
        row = cols.get((layer, name))
        if not row or row["description"] != meaning[name][1]:
            bad.append(f"{layer}.{name}: gpkg_data_columns {row} != array_units {meaning[name]}")
        elif meaning[name][0] == "m" and not row["title"].endswith("m)"):
            bad.append(f"{layer}.{name}: title {row['title']!r} does not give the unit m")
for key in (("conduits", "length"), ("conduits", "tunnel_type_name"), ("key_points", "name")):
    if key not in cols: bad.append(f"no gpkg_data_columns row for {key}")
for b in bad[:20]:
    print("FAIL:", b)
print(f"ok: {n_edges} conduits, {n_nodes} nodes, {len(kps)} key points, every attribute, geometry, "
      "style, units")
sys.exit(1 if bad else 0)
PY

# 2. A crs in run.json (the scenario's, issue 12; run.json writes "crs": null without one,
# here set by hand): that CRS.
cp -r "$T/gen" "$T/crs"
sed -i 's|^  "crs": null|  "crs": "EPSG:2154"|' "$T/crs/run.json"
grep -q '"crs": "EPSG:2154"' "$T/crs/run.json" || fail "could not edit run.json"
"$KARST" export "$T/crs" --gpkg "$T/crs.gpkg" >"$T/out.txt" || fail "export with crs"
grep -q "coordinate system EPSG:2154 (from $T/crs/run.json:" "$T/out.txt" || fail "summary: $(cat "$T/out.txt")"
for layer in conduits nodes key_points; do
  ogrinfo -ro -so "$T/crs.gpkg" "$layer" >"$T/l.txt"
  grep -q 'PROJCRS\["RGF93 v1 / Lambert-93"' "$T/l.txt" && grep -q 'ID\["EPSG",2154\]' "$T/l.txt" \
    || { cat "$T/l.txt"; fail "$layer is not in EPSG:2154"; }
  grep -q "^Feature Count: $(ogrinfo -ro -so "$T/gen.gpkg" "$layer" | sed -n 's/^Feature Count: //p')$" "$T/l.txt" \
    || fail "$layer feature count changed with the CRS"
done
# ... also as an EPSG number inside "parameters".
cp -r "$T/gen" "$T/num"
sed -i 's|^    "crs": null,|    "crs": 32634,|' "$T/num/run.json"
"$KARST" export "$T/num" --gpkg "$T/num.gpkg" -q || fail "export with a numeric crs"
ogrinfo -ro -so "$T/num.gpkg" conduits | grep -q 'ID\["EPSG",32634\]' || fail "numeric crs 32634 not written"
echo "ok: run.json's crs (EPSG:2154 at the top level, 32634 in parameters) is the layers' CRS"

# 3. A survey with its own CS (Dow-Providence, EPSG:7405), and --crs overriding it.
"$KARST" export "$SRC/datasets/surveys/dowprov/DowProv.3d" --gpkg "$T/dow.gpkg" -q || fail "export survey"
ogrinfo -ro -so "$T/dow.gpkg" nodes >"$T/l.txt"
grep -q 'ID\["EPSG",7405\]' "$T/l.txt" || fail "survey CRS EPSG:7405 not written"
grep -q "^Feature Count: 692$" "$T/l.txt" || fail "survey nodes (karst metrics: 692)"
grep -q "^label: String" "$T/l.txt" || fail "survey station labels"
ogrinfo -ro -so "$T/dow.gpkg" conduits | grep -q "^Feature Count: 689$" || fail "survey legs (karst metrics: 689)"
ogrinfo -ro -so "$T/dow.gpkg" key_points | grep -q "^Feature Count: 0$" || fail "a survey has no key points"
"$KARST" export "$SRC/datasets/surveys/dowprov/DowProv.3d" --gpkg "$T/dow2.gpkg" --crs EPSG:27700 -q \
  || fail "export --crs"
ogrinfo -ro -so "$T/dow2.gpkg" nodes | grep -q 'ID\["EPSG",27700\]' || fail "--crs EPSG:27700 not written"
"$KARST" export "$T/crs" --gpkg "$T/crs2.gpkg" --crs EPSG:32634 -q || fail "export --crs over run.json"
ogrinfo -ro -so "$T/crs2.gpkg" conduits | grep -q 'ID\["EPSG",32634\]' || fail "--crs did not override run.json"
echo "ok: a survey's own CS, and --crs over it and over run.json"

# 4. An ensemble member directory: key points and crs from ensemble.json, the member's seed.
"$KARST" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 2 -j 1 -o "$T/ens" -q || fail "ensemble"
"$KARST" export "$T/ens/realisations/0001" --gpkg "$T/m1.gpkg" -q || fail "export member"
seed=$(sed -n '2s/^1,\([0-9]*\),.*/\1/p' "$T/ens/realisations/0001/metrics.csv")
ogrinfo -ro -so "$T/m1.gpkg" key_points >"$T/l.txt"
grep -q "^Feature Count: 17$" "$T/l.txt" || fail "member key points (17 in branchwork.yaml)"
grep -q "^  seed=$seed$" "$T/l.txt" && grep -q "^  member=1$" "$T/l.txt" || { cat "$T/l.txt"; fail "member seed $seed"; }
echo "ok: an ensemble member keeps its key points and its own seed"

# 4b. Reproducible files: with SOURCE_DATE_EPOCH the two exports, a second apart, are
# byte-identical, and every clock reading in the file is that time (1700000000 s after the
# epoch is 2023-11-14 22:13:20 UTC, by hand: 19675 days = 2023-11-14, plus 80000 s).
SOURCE_DATE_EPOCH=1700000000 "$KARST" export "$T/gen" --gpkg "$T/r1.gpkg" -q || fail "export r1"
sleep 1.1
SOURCE_DATE_EPOCH=1700000000 "$KARST" export "$T/gen" --gpkg "$T/r2.gpkg" -q || fail "export r2"
cmp -s "$T/r1.gpkg" "$T/r2.gpkg" || fail "the same input and SOURCE_DATE_EPOCH gave different GeoPackages"
cmp -s "$T/r1.qml" "$T/r2.qml" || fail "the same input gave different .qml files"
stamps=$( (ogrinfo -ro -q "$T/r1.gpkg" -sql "SELECT DISTINCT last_change FROM gpkg_contents"
  ogrinfo -ro -q "$T/r1.gpkg" -sql "SELECT DISTINCT update_time FROM layer_styles") \
  | sed -n 's/^ *\(last_change\|update_time\)[^=]*= *//p' | sort -u)
[ "$stamps" = "2023/11/14 22:13:20+00" ] || fail "timestamps are not SOURCE_DATE_EPOCH's: $stamps"
ogrinfo -ro -q "$T/gen.gpkg" -sql "SELECT DISTINCT last_change FROM gpkg_contents" | grep -q "2023-11-14" \
  && fail "without SOURCE_DATE_EPOCH the export was stamped with it"
echo "ok: SOURCE_DATE_EPOCH makes the GeoPackage byte-identical ($stamps)"

# 5. Bad input: message, exit 1, nothing new, an existing output untouched.
cp "$T/gen.gpkg" "$T/keep.gpkg"
cp "$T/gen.qml" "$T/keep.qml"
sum=$(cat "$T/keep.gpkg" "$T/keep.qml" | md5sum)
expect() { # exit pattern command...
  local want=$1 pat=$2; shift 2
  "$@" >"$T/err.txt" 2>&1; local got=$?
  [ "$got" = "$want" ] || { cat "$T/err.txt"; fail "$*: exit $got, expected $want"; }
  grep -q -- "$pat" "$T/err.txt" || { cat "$T/err.txt"; fail "$*: message lacks '$pat'"; }
  echo "ok: $pat"
}
expect 1 "karst export: --crs: coordinate system 'EPSG:99999' is not one GDAL/PROJ knows" \
  "$KARST" export "$T/gen" --gpkg "$T/keep.gpkg" --crs EPSG:99999
cp -r "$T/gen" "$T/badcrs"
sed -i 's|^  "crs": null,|  "crs": "not a crs",|' "$T/badcrs/run.json"
line=$(grep -n '^  "crs"' "$T/badcrs/run.json" | cut -d: -f1)
expect 1 "karst export: $T/badcrs/run.json:$line:10: coordinate system 'not a crs' is not one GDAL/PROJ knows" \
  "$KARST" export "$T/badcrs" --gpkg "$T/keep.gpkg"
sed -i 's|"crs": "not a crs"|"crs": [1]|' "$T/badcrs/run.json"
expect 1 "karst export: $T/badcrs/run.json:$line:10: crs must be a coordinate system" \
  "$KARST" export "$T/badcrs" --gpkg "$T/keep.gpkg"
sed -i 's|"crs": \[1\]|"crs": "EPSG:2154",|' "$T/badcrs/run.json"
expect 1 "karst export: $T/badcrs/run.json:$line:" "$KARST" export "$T/badcrs" --gpkg "$T/keep.gpkg"
sed -i 's|"crs": "EPSG:2154",,|"crs": null,|; s|"type": "spring"|"type": "fountain"|' "$T/badcrs/run.json"
expect 1 "type must be sink, spring or waypoint, got 'fountain'" "$KARST" export "$T/badcrs" --gpkg "$T/keep.gpkg"
for v in 12x -5 ' 7' 999999999999999999999; do
  expect 1 "karst export: SOURCE_DATE_EPOCH: '$v' is not a number of seconds since 1970-01-01 UTC" \
    env SOURCE_DATE_EPOCH="$v" "$KARST" export "$T/gen" --gpkg "$T/keep.gpkg"
done
expect 1 "timestamp 99999999999999 is not a date before year 10000" \
  env SOURCE_DATE_EPOCH=99999999999999 "$KARST" export "$T/gen" --gpkg "$T/keep.gpkg"
[ "$(cat "$T/keep.gpkg" "$T/keep.qml" | md5sum)" = "$sum" ] || fail "a failed export changed the previous output"
expect 1 "a GeoPackage name must end in .gpkg" "$KARST" export "$T/gen" --gpkg "$T/out.shp"
expect 1 "no network.vtp in this directory" "$KARST" export "$T" --gpkg "$T/x.gpkg"
expect 1 "karst export: $T/missing.3d" "$KARST" export "$T/missing.3d" --gpkg "$T/x.gpkg"
expect 1 "$T/nodir/x.gpkg" "$KARST" export "$T/gen" --gpkg "$T/nodir/x.gpkg"
mkdir "$T/ro" && chmod a-w "$T/ro"
if [ "$(id -u)" != 0 ]; then
  expect 1 "$T/ro/x.gpkg" "$KARST" export "$T/gen" --gpkg "$T/ro/x.gpkg"
fi
expect 2 "no output given (--gpkg OUT.gpkg)" "$KARST" export "$T/gen"
expect 2 "no directory or network file given" "$KARST" export --gpkg "$T/x.gpkg"
expect 2 "--crs needs a value" "$KARST" export "$T/gen" --gpkg "$T/x.gpkg" --crs
[ -e "$T/x.gpkg" ] || [ -e "$T/out.shp" ] && fail "a failed export left an output"
ls -a "$T" | grep -q "tmp" && fail "a failed export left a temporary: $(ls -a "$T")"
echo "ok: export"
