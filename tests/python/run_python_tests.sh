#!/usr/bin/env bash
# Runs tests/python/test_karst.py (unittest) against this build's karst package.
#   run_python_tests.sh PYTHONPATH KARST_CLI SOURCE_DIR [LD_PRELOAD]
# In the ASan + UBSan build the extension is instrumented but /usr/bin/python3 is not, so the
# sanitizer runtime is preloaded (LD_PRELOAD of gcc's libasan.so, which must come first in the
# process). Memory errors and undefined behaviour then abort the test as everywhere else.
# Leaks: CPython and numpy leave memory unreachable at exit by design, so LeakSanitizer's report
# (written to files, PYTHONMALLOC=malloc so that every Python object goes through malloc) is
# read by lsan_report.py, and the test fails on any leak allocated from karst's own code.
set -u
PYPATH=$(cd "$1" && pwd)
CLI=$2
SRC=$(cd "$3" && pwd)
PRELOAD=${4:-}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
export PYTHONPATH="$PYPATH" KARST_CLI="$CLI" KARST_SOURCE_DIR="$SRC" PYTHONDONTWRITEBYTECODE=1
cd "$SRC/tests/python"
if [ -z "$PRELOAD" ]; then
  exec /usr/bin/python3 -m unittest -v test_karst
fi
mkdir "$T/lsan"
# numpy's module initialisation allocates tables it never frees.
printf 'leak:PyInit__multiarray_umath\nleak:initumath\n' >"$T/lsan.supp"
LD_PRELOAD="$PRELOAD" PYTHONMALLOC=malloc \
  ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=1:fast_unwind_on_malloc=0:log_path=$T/lsan/report" \
  LSAN_OPTIONS="suppressions=$T/lsan.supp:print_suppressions=0:exitcode=0" \
  /usr/bin/python3 -m unittest -v test_karst
status=$?
/usr/bin/python3 "$SRC/tests/python/lsan_report.py" "$T/lsan" || status=1
exit $status
