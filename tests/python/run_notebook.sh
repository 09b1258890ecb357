#!/usr/bin/env bash
# Executes analysis/ensemble_vs_survey.ipynb with Debian's jupyter nbconvert, in a kernel that
# imports the karst package of this build, and checks the executed notebook: every cell ran
# without error, the plots are there (three PNG figures), and the notebook's own checks (the
# survey's percentiles recomputed with numpy) printed their result.
#   run_notebook.sh PYTHONPATH SOURCE_DIR [LD_PRELOAD]
# An ASan build passes its libasan as LD_PRELOAD: the sanitizer runtime must come first in a
# process, and /usr/bin/python3 is not instrumented. Only the kernel, the process that loads
# karst, gets it (through its kernel spec); Jupyter itself runs as usual. The kernel's sanitizer
# reports are read as in run_python_tests.sh (lsan_report.py).
set -u
PYPATH=$(cd "$1" && pwd)
SRC=$(cd "$2" && pwd)
PRELOAD=${3:-}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v jupyter >/dev/null || fail "jupyter is required (scripts/install-deps installs jupyter-nbconvert)"

mkdir -p "$T/jupyter/kernels/karst-test" "$T/lsan"
printf 'leak:PyInit__multiarray_umath\nleak:initumath\n' >"$T/lsan.supp"
/usr/bin/python3 - "$T/jupyter/kernels/karst-test/kernel.json" "$PYPATH" "$PRELOAD" "$T/lsan" <<'PY'
import json, os, sys
out, pypath, preload, lsan = sys.argv[1:]
env = {"PYTHONPATH": pypath}
if preload:
    # As run_python_tests.sh: the report goes to files that lsan_report.py reads, but with the
    # fast (frame-pointer) unwinder, as the exact one makes every malloc of IPython's start-up
    # slow; the frames of karst's own code, built with frame pointers, are still recorded.
    env["LD_PRELOAD"] = preload
    env["PYTHONMALLOC"] = "malloc"
    env["ASAN_OPTIONS"] = os.environ.get("ASAN_OPTIONS", "") + \
        f":detect_leaks=1:log_path={lsan}/report"
    env["LSAN_OPTIONS"] = f"suppressions={lsan}.supp:print_suppressions=0:exitcode=0"
    env["UBSAN_OPTIONS"] = os.environ.get("UBSAN_OPTIONS", "")
json.dump({"argv": ["/usr/bin/python3", "-m", "ipykernel_launcher", "-f", "{connection_file}"],
           "display_name": "karst test", "language": "python", "env": env}, open(out, "w"))
PY
# The kernel's children (none in the notebook today) must not inherit the preloaded runtime.
mkdir -p "$T/ipython/profile_default/startup"
echo 'import os; os.environ.pop("LD_PRELOAD", None)' >"$T/ipython/profile_default/startup/00-karst-test.py"
export JUPYTER_PATH="$T/jupyter" JUPYTER_CONFIG_DIR="$T/config" JUPYTER_RUNTIME_DIR="$T/runtime"
export IPYTHONDIR="$T/ipython" MPLCONFIGDIR="$T/mpl" PYDEVD_DISABLE_FILE_VALIDATION=1
# The Jupyter processes themselves must not inherit the sanitizer options meant for the kernel.
unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS
jupyter nbconvert --to notebook --execute --ExecutePreprocessor.kernel_name=karst-test \
  --ExecutePreprocessor.timeout=3000 --ExecutePreprocessor.startup_timeout=600 \
  --output-dir "$T/out" "$SRC/analysis/ensemble_vs_survey.ipynb" \
  >"$T/log" 2>&1 \
  || { cat "$T/log"; fail "jupyter nbconvert --execute"; }
/usr/bin/python3 - "$T/out/ensemble_vs_survey.ipynb" <<'PY' || fail "executed notebook"
import json, sys
nb = json.load(open(sys.argv[1]))
code = [c for c in nb["cells"] if c["cell_type"] == "code"]
outs = [o for c in code for o in c.get("outputs", [])]
bad = []
if any(c.get("execution_count") is None for c in code): bad.append("a code cell did not run")
errors = [o for o in outs if o["output_type"] == "error"]
if errors: bad.append(f"errors: {errors[0]['ename']}: {errors[0]['evalue']}")
pngs = sum(1 for o in outs if "image/png" in o.get("data", {}))
if pngs != 3: bad.append(f"{pngs} figures, expected 3")
text = "".join("".join(o.get("text", "")) for o in outs if o["output_type"] == "stream")
for want in ("percentiles checked against numpy for", "<karst.Ensemble 'branchwork'", "in EPSG:7405"):
    if want not in text: bad.append(f"no output '{want}'")
for b in bad: print("FAIL:", b)
print(f"ok: {len(code)} cells ran, {pngs} figures")
sys.exit(1 if bad else 0)
PY
if [ -n "$PRELOAD" ]; then
  /usr/bin/python3 "$SRC/tests/python/lsan_report.py" "$T/lsan" || fail "sanitizer findings in the kernel"
fi
echo "ok: analysis/ensemble_vs_survey.ipynb"
