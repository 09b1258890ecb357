#!/usr/bin/env bash
# karst view: finds the ParaView script karst wrote, runs ParaView on it in the script's
# directory ($KARST_PARAVIEW stands in for paraview here: a fake that records how it was run),
# prints the command when ParaView is missing, and says clearly what is wrong otherwise; and
# every array of the outputs (generate --samples with geology.vtp, mesh --sdf) states a unit
# karst knows.
# ParaView itself runs the scripts in test_paraview.sh.
#   bash test_view.sh KARST_BINARY SOURCE_DIR
set -u
KARST=$1
SRC=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail=0
no() { echo "FAIL: $*"; fail=1; }

gen="$out/run 'one'"
"$KARST" generate "$SRC/datasets/scenarios/branchwork.yaml" -o "$gen" --samples --quiet ||
  { echo "FAIL: generate"; exit 1; }
[ -f "$gen/network.paraview.py" ] || no "karst generate wrote no network.paraview.py"

# No ParaView: the command to run, shell-quoted, exit 0.
got=$(env -u KARST_PARAVIEW PATH=/usr/bin:/bin "$KARST" view "$gen" 2>&1); rc=$?
want="cd '$out/run '\\''one'\\''' && paraview --script=network.paraview.py"
[ $rc -eq 0 ] || no "view without ParaView exited $rc"
case "$got" in *"ParaView is not installed"*"$want"*) echo "ok: prints $want" ;;
  *) no "view without ParaView printed: $got (expected $want)" ;; esac
got=$(KARST_PARAVIEW=/bin/false "$KARST" view "$gen" --print 2>&1)
[ "$got" = "$want" ] || no "--print printed '$got'"
# The printed command works in a shell: it changes into the directory.
( eval "${want% && *}" && [ "$PWD" = "$(realpath "$gen")" ] ) || no "the printed 'cd' does not reach $gen"

# A fake ParaView: records its working directory and arguments.
fake="$out/fake-paraview"
cat >"$fake" <<EOF
#!/bin/sh
{ pwd; for a in "\$@"; do echo "\$a"; done; } >"$out/ran.txt"
exit \${FAKE_STATUS:-0}
EOF
chmod +x "$fake"
KARST_PARAVIEW="$fake" "$KARST" view "$gen" || no "view with ParaView exited $?"
if [ "$(sed -n 1p "$out/ran.txt")" = "$(realpath "$gen")" ] &&
  [ "$(sed -n 2p "$out/ran.txt")" = "--script=network.paraview.py" ] && [ "$(wc -l <"$out/ran.txt")" = 2 ]; then
  echo "ok: runs paraview --script=network.paraview.py in the script's directory"
else
  no "ParaView was run as: $(cat "$out/ran.txt")"
fi
err=$(FAKE_STATUS=3 KARST_PARAVIEW="$fake" "$KARST" view "$gen" 2>&1); rc=$?
[ $rc -eq 1 ] && [[ "$err" == *"exited with status 3"* ]] || no "a failing ParaView: exit $rc, '$err'"

# Two scripts in one directory: name one; a data file finds the script beside it.
"$KARST" mesh "$gen/network.vtp" -o "$gen/cave.vtp" --voxel 3 --sdf "$gen/cave.vti" --quiet || no "mesh"
# Every array of every output states a unit karst knows (docs/arrays.md): read with VTK.
/usr/bin/python3 - "$gen" <<'PY' || no "an output holds an array without a known unit"
import sys, vtk
for name, reader in (("network.vtp", vtk.vtkXMLPolyDataReader), ("samples.vtp", vtk.vtkXMLPolyDataReader),
                     ("geology.vtp", vtk.vtkXMLPolyDataReader),
                     ("cave.vtp", vtk.vtkXMLPolyDataReader), ("cave.vti", vtk.vtkXMLImageDataReader)):
    r = reader()
    r.SetFileName(sys.argv[1] + "/" + name)
    r.Update()
    o = r.GetOutput()
    t = o.GetFieldData().GetAbstractArray("array_units")
    rows = {t.GetValue(3 * i): t.GetValue(3 * i + 1) for i in range(t.GetNumberOfTuples())}
    arrays = [o.GetPointData().GetArrayName(i) for i in range(o.GetPointData().GetNumberOfArrays())]
    arrays += [o.GetCellData().GetArrayName(i) for i in range(o.GetCellData().GetNumberOfArrays())]
    for a in arrays:
        assert rows.get(a) not in (None, "unknown"), "%s: %s has unit %r" % (name, a, rows.get(a))
    # "feature" means what a polygon is in geology.vtp, a surface detail in a mesh: each file
    # states its own meaning (the entries of src/arrays/arrays.c for that kind of file).
    meaning = {t.GetValue(3 * i): t.GetValue(3 * i + 2) for i in range(t.GetNumberOfTuples())}
    if name == "geology.vtp":
        assert meaning["feature"].startswith("what the polygon is"), meaning["feature"]
    if name == "cave.vtp" and "feature" in meaning:
        assert meaning["feature"].startswith("what the triangle belongs to"), meaning["feature"]
    print("ok: %s: %s" % (name, ", ".join("%s [%s]" % (a, rows[a]) for a in arrays)))
PY
[ -f "$gen/cave.paraview.py" ] || no "karst mesh wrote no cave.paraview.py"
err=$("$KARST" view "$gen" --print 2>&1); rc=$?
[ $rc -eq 1 ] && [[ "$err" == *"2 ParaView scripts (cave.paraview.py, network.paraview.py)"* ]] ||
  no "two scripts: exit $rc, '$err'"
got=$("$KARST" view "$gen/cave.vtp" --print 2>&1)
[[ "$got" == *"--script=cave.paraview.py" ]] || no "view FILE printed '$got'"

# Errors and usage.
err=$("$KARST" view "$out/nothing" 2>&1); rc=$?
[ $rc -eq 1 ] && [[ "$err" == *"$out/nothing"* ]] || no "a missing directory: exit $rc, '$err'"
"$KARST" view >/dev/null 2>&1; [ $? -eq 2 ] || no "no argument is not a usage error"
"$KARST" view "$gen" --bogus >/dev/null 2>&1; [ $? -eq 2 ] || no "an unknown option is not a usage error"
"$KARST" help view | grep -q "usage: karst view" || no "karst help view"
[ $fail -eq 0 ] && echo "ok: karst view"
exit $fail
