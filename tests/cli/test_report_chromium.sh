#!/usr/bin/env bash
# The HTML report renders in headless Debian Chromium without any console error and with
# every plot present.
#   bash test_report_chromium.sh KARST_BINARY SOURCE_DIR   end to end: karst ensemble on the
#        branchwork scenario, karst report, then the check below (ctest runs this)
#   bash test_report_chromium.sh --check REPORT.html N     only the check: N <svg> elements
# The page has no scripts, so any CONSOLE line (a failed resource, a parse error) is a failure.
set -u

check_report() { # HTML EXPECTED_SVG_COUNT
  local html=$1 want=$2 tmp
  tmp=$(mktemp -d)
  timeout 180 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$tmp/profile" --enable-logging=stderr --v=0 \
    --dump-dom "file://$(realpath "$html")" >"$tmp/dom.html" 2>"$tmp/log.txt"
  local rc=$? fail=0
  if [ $rc -ne 0 ]; then echo "FAIL: chromium exited with $rc"; cat "$tmp/log.txt"; fail=1; fi
  if grep -q "CONSOLE" "$tmp/log.txt"; then
    echo "FAIL: console messages while rendering $html:"; grep "CONSOLE" "$tmp/log.txt"; fail=1
  fi
  local got
  got=$(grep -o "<svg " "$tmp/dom.html" | wc -l)
  if [ "$got" != "$want" ]; then
    echo "FAIL: $got <svg> elements in the rendered DOM, expected $want"; fail=1
  else
    echo "ok: $got plots rendered, no console message"
  fi
  # Every plot has a frame or a note: an <svg> with nothing drawn is a missing plot.
  local empty
  empty=$(/usr/bin/python3 - "$tmp/dom.html" <<'PY'
import re, sys
dom = open(sys.argv[1], encoding="utf-8").read()
svgs = re.findall(r"<svg .*?</svg>", dom, re.S)
print(sum(1 for s in svgs if not re.search(r"<(rect|path|polygon|line|circle|text)", s)))
PY
)
  if [ "$empty" != "0" ]; then echo "FAIL: $empty empty plots"; fail=1; fi
  rm -rf "$tmp"
  return $fail
}

if [ "${1:-}" = "--check" ]; then
  check_report "$2" "$3"
  exit $?
fi

KARST=$1
SRC=$2
if ! command -v chromium >/dev/null 2>&1; then
  echo "FAIL: chromium is not installed (scripts/install-deps installs it)"
  exit 1
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if ! "$KARST" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 6 -o "$out/ens" -j 2 --seed 3 \
  --quiet 2>"$out/err.txt"; then
  echo "FAIL: karst ensemble"; cat "$out/err.txt"; exit 1
fi
"$KARST" report "$out/ens" --survey "$SRC/datasets/surveys/karstnet/Sakany_nodes.dat" -o "$out/report.html" \
  --members 2 || { echo "FAIL: karst report"; exit 1; }
nmetrics=$(head -1 "$out/ens/metrics.csv" | tr ',' '\n' | tail -n +3 | wc -l)
# histograms + rose + degree distribution + 2 members x (plan, section)
check_report "$out/report.html" $((nmetrics + 2 + 4)) || exit 1
# The real parameters (17 key points, fracture families, horizons: each one table) are all
# shown with their values, read back independently.
/usr/bin/python3 "$SRC/tests/python/check_report_parameters.py" "$out/report.html" "$out/ens" ||
  { echo "FAIL: the parameters of the page differ from ensemble.json"; exit 1; }
n=$(grep -o '<table class="json rows">' "$out/report.html" | wc -l)
if [ "$n" -lt 3 ]; then echo "FAIL: $n one-table arrays, expected at least 3"; exit 1; fi
echo "ok: $n arrays of same-keyed objects shown as one table each"
