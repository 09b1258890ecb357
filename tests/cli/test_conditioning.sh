#!/usr/bin/env bash
# Conditioning on a survey, coordinates and generations (issue 12) on the real binary, checked
# against independent programs: Survex's cavern + dump3d for the survey, PROJ's cs2cs for the
# coordinates, VTK (python3-vtk9) to read the networks back (tests/tools/check_conditioned.py).
#  - every surveyed leg of DowProv is in every member, at Survex's positions to 1 mm, observed = 1,
#    station coordinates byte-identical across members; -j 1, -j 2 and mpirun -np 2 write the
#    same files;
#  - the same survey in a UTM 30N scenario lands where cs2cs puts cavern's stations, to 1 mm; a
#    latitude/longitude key point where cs2cs puts it, to 1 mm;
#  - run.json, network.vtp, geology.vtp, samples.vtp, ensemble.json and the report record the CRS;
#  - a survey outside the domain or above the terrain is refused, saying by how much;
#  - a two-generation run lays generation-2 conduits near its own water table and follows
#    generation-1 conduits more, the cheaper they are (cohesion).
set -u
KARST=$1
SRC=$(cd "$2" && pwd)
PY=/usr/bin/python3
CHECK="$PY $SRC/tests/tools/check_conditioned.py"
fail=0
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1"; fail=1; }
for tool in cavern dump3d cs2cs; do
  command -v $tool >/dev/null || { echo "FAIL: $tool not found (scripts/install-deps installs it)"; exit 1; }
done

# Survex's own reduction of the survey, the reference for every comparison below.
cavern -o "$T/ref.3d" "$SRC/datasets/surveys/dowprov/DowProv.svx" >"$T/cavern.log" 2>&1 ||
  { cat "$T/cavern.log"; echo "FAIL: cavern"; exit 1; }
dump3d "$T/ref.3d" >"$T/ref.dump"

# A light copy of the shipped example (coarser sampling, absolute paths) for the ensembles.
sed -e 's/fill_radius: 30/fill_radius: 60/; s/feature_radius: 20/feature_radius: 45/; s/k: 24/k: 16/' \
    -e "s#heightfield: dowprov/terrain.asc#heightfield: $SRC/datasets/scenarios/dowprov/terrain.asc#" \
    -e "s#- ../surveys/dowprov/DowProv.3d#- $SRC/datasets/surveys/dowprov/DowProv.svx#" \
    "$SRC/datasets/scenarios/dowprov_extension.yaml" >"$T/ext.yaml"
grep -q "fill_radius: 60" "$T/ext.yaml" && grep -q "DowProv.svx" "$T/ext.yaml" || bad "light copy of dowprov_extension.yaml"

# --- ensembles: every leg in every member, byte-identical for -j 1, -j 2, mpirun -np 2 ---------
N=3
"$KARST" ensemble "$T/ext.yaml" -n $N -o "$T/e1" -j 1 --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "ensemble -j 1"; }
"$KARST" ensemble "$T/ext.yaml" -n $N -o "$T/e2" -j 2 --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "ensemble -j 2"; }
same() { # dir dir: every file but the run log ensemble_log.json
  (cd "$1" && find . -type f ! -name ensemble_log.json | sort) >"$T/l1"
  (cd "$2" && find . -type f ! -name ensemble_log.json | sort) >"$T/l2"
  cmp -s "$T/l1" "$T/l2" || return 1
  while read -r f; do cmp -s "$1/$f" "$2/$f" || { echo "  differs: $f"; return 1; }; done <"$T/l1"
}
same "$T/e1" "$T/e2" && ok "conditioned ensemble: -j 1 and -j 2 byte-identical" || bad "-j 1 and -j 2 differ"
if mpirun --allow-run-as-root --oversubscribe -np 2 -x ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    "$KARST" ensemble "$T/ext.yaml" -n $N -o "$T/em" -j 1 --quiet >"$T/mpi.log" 2>&1; then
  same "$T/e1" "$T/em" && ok "conditioned ensemble: mpirun -np 2 byte-identical" || bad "mpirun -np 2 differs"
elif grep -q "but this karst was built without MPI" "$T/mpi.log"; then
  ok "a build without MPI refuses mpirun (MPI identity is checked by MPI builds)"
else
  cat "$T/mpi.log"; bad "mpirun -np 2"
fi
for m in $(cd "$T/e1/realisations" && ls -d [0-9]*); do
  $CHECK "$T/e1/realisations/$m/network.vtp" "$T/ref.dump" --names "$T/names_$m.txt" || bad "member $m"
done
first=""
for f in "$T"/names_*.txt; do
  [ -z "$first" ] && first=$f && continue
  cmp -s "$first" "$f" && ok "station coordinates byte-identical in $(basename "$first") and $(basename "$f")" ||
    bad "station coordinates differ between members"
done
# Members differ elsewhere: the simulated parts are not all the same.
a=0000; b=$(printf %04d $((N - 1)))
cmp -s "$T/e1/realisations/$a/network.vtp" "$T/e1/realisations/$b/network.vtp" &&
  bad "members $a and $b are identical" || ok "members differ outside the survey"
grep -q '"crs": "EPSG:7405"' "$T/e1/ensemble.json" && ok "ensemble.json records the CRS" || bad "ensemble.json: no crs"
"$KARST" report "$T/e1" -o "$T/report.html" >"$T/log" 2>&1 || { cat "$T/log"; bad "report"; }
grep -q "EPSG:7405" "$T/report.html" && ok "the report names the CRS" || bad "report: no CRS"
grep -q "unexplored" "$T/report.html" && grep -q 'id="density"' "$T/report.html" &&
  ok "the report has the density map of simulated conduits" || bad "report: no density map"

# --- one run: run.json and every .vtp record the CRS ---------------------------------------------
"$KARST" generate "$T/ext.yaml" -o "$T/g" --samples --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "generate"; }
$PY - "$T/g" <<'PYEOF' || fail=1
import json, sys, vtk
d = sys.argv[1]
run = json.load(open(d + "/run.json"))
assert run["crs"] == "EPSG:7405" and run["parameters"]["crs"] == "EPSG:7405", run.get("crs")
c = run["parameters"]["conditioning"]
assert c["legs"] == 689 and run["counts"]["observed_edges"] == 689, c
for f in ("network.vtp", "geology.vtp", "samples.vtp"):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + "/" + f); r.Update()
    a = r.GetOutput().GetFieldData().GetAbstractArray("crs")
    assert a is not None and a.GetValue(0) == "EPSG:7405", f
print("ok: run.json, network.vtp, geology.vtp and samples.vtp record EPSG:7405; 689 legs")
PYEOF

# --- another CRS: the survey converted into UTM 30N, a latitude/longitude key point ------------
# Domain: the example's, converted by cs2cs (EPSG:27700 -> EPSG:32630) and rounded outwards.
cat >"$T/utm.yaml" <<YAML
name: dowprov_utm
crs: UTM 30N
domain: {min: [563300, 6000600, 250], max: [564700, 6002500, 700]}
terrain: {elevation: 600}
water_table: {elevation: 320}
fractures: [{dip_direction: 45, dip: 88, weight: 1}]
key_points:
  - {name: spring, type: spring, position: [563500, 6002150, 320]}
  - {name: fell, type: sink, latitude: 54.15731224, longitude: -2.01527792, elevation: 470}
conditioning:
  surveys: [{file: $SRC/datasets/surveys/dowprov/DowProv.svx}]
  sinks: entrances
sampling: {fill_radius: 60, feature_radius: 45, k: 16}
YAML
"$KARST" generate "$T/utm.yaml" -o "$T/u" --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "generate in UTM 30N"; }
$CHECK "$T/u/network.vtp" "$T/ref.dump" --to EPSG:32630 || bad "survey converted to UTM 30N"
want=$(echo "54.15731224 -2.01527792 470" | cs2cs -f %.6f EPSG:4326 EPSG:32630)
$PY - "$T/u/run.json" $want <<'PYEOF' || fail=1
import json, sys
run = json.load(open(sys.argv[1]))
kp = [k for k in run["parameters"]["key_points"] if k["name"] == "fell"][0]["position"]
want = [float(v) for v in sys.argv[2:5]]
d = max(abs(a - b) for a, b in zip(kp, want))
assert d <= 1e-3, "latitude/longitude key point at %s, cs2cs says %s (%.4f m)" % (kp, want, d)
assert run["crs"] == "UTM 30N"
print("ok: the latitude/longitude key point lands %.2e m from cs2cs's UTM 30N position" % d)
PYEOF

# --- refusals: outside the domain, above the terrain -----------------------------------------
refused() { # description yaml pattern...
  local what=$1 y=$2; shift 2
  "$KARST" generate "$y" -o "$T/refused" --quiet >"$T/out" 2>&1; local got=$?
  if [ "$got" != 1 ]; then bad "$what: exit $got, expected 1"; cat "$T/out"; return; fi
  for p in "$@"; do grep -qF -- "$p" "$T/out" || { bad "$what: message lacks '$p'"; cat "$T/out"; return; }; done
  [ ! -e "$T/refused" ] || { bad "$what: wrote $T/refused"; return; }
  ok "$what is refused: $(head -c 300 "$T/out")"
}
sed 's/min: \[398200, 472750, 250\]/min: [398500, 472750, 250]/' "$T/ext.yaml" >"$T/out_domain.yaml"
refused "a survey outside the domain" "$T/out_domain.yaml" "outside the domain" "122.00 m beyond it in x" "DowProv.svx"
sed 's/^  heightfield: .*/  elevation: 380/' "$T/ext.yaml" >"$T/above.yaml"
refused "a survey above the terrain" "$T/above.yaml" "above the terrain" "m above the ground" "DowProv.svx"

# --- two generations ---------------------------------------------------------------------------
G=$SRC/tests/data/scenarios/two_generations.yaml
"$KARST" generate "$G" -o "$T/gen" --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "two generations"; }
sed 's/cohesion: 0.3/cohesion: 1/' "$G" >"$T/gen_c1.yaml"
"$KARST" generate "$T/gen_c1.yaml" -o "$T/gen1" --quiet >"$T/log" 2>&1 || { cat "$T/log"; bad "cohesion 1"; }
$PY - "$T/gen" "$T/gen1" <<'PYEOF' || fail=1
import json, sys, vtk
def edges(d):
    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(d + "/network.vtp"); r.Update()
    pd = r.GetOutput(); g = pd.GetCellData().GetArray("generation"); ids = vtk.vtkIdList(); out = {}
    for c in range(pd.GetNumberOfCells()):
        pd.GetCellPoints(c, ids)
        z = (pd.GetPoint(ids.GetId(0))[2] + pd.GetPoint(ids.GetId(1))[2]) / 2
        out.setdefault(int(g.GetValue(c)), []).append(z)
    return out
def median(v):
    v = sorted(v); return v[len(v) // 2]
e = edges(sys.argv[1])
WT1, WT2 = 100.0, 40.0  # the water tables of tests/data/scenarios/two_generations.yaml
m1, m2 = median(e[1]), median(e[2])
assert abs(m1 - WT1) < abs(m1 - WT2), "generation 1 median z %.1f m is not near its water table" % m1
assert abs(m2 - WT2) < abs(m2 - WT1), "generation 2 median z %.1f m is not near its water table" % m2
g03 = json.load(open(sys.argv[1] + "/run.json"))["generations"][1]["reactivated_length"]
g1 = json.load(open(sys.argv[2] + "/run.json"))["generations"][1]["reactivated_length"]
assert g03 > 0 and g03 > g1, "generation 2 follows %.1f m of generation 1 at cohesion 0.3, %.1f m at 1" % (g03, g1)
print("ok: generation medians z %.1f m (water table 100 m) and %.1f m (40 m); generation 2 follows "
      "%.1f m of older conduits at cohesion 0.3, %.1f m at cohesion 1" % (m1, m2, g03, g1))
PYEOF
exit $fail
