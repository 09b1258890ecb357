#!/usr/bin/env bash
# The HTML report renders in headless Debian Chromium without any console error, with every
# plot present, every bar at least 2 px wide and filled, no two text boxes overlapping and no
# text over the data (measured in the page: tests/python/report_layout.js), a unit on every
# axis, and only relative, normalised paths.
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
  # Layout as rendered: a copy of the page with tests/python/report_layout.js at its end
  # measures every bar and text box (getBoundingClientRect) and writes the result into the DOM.
  /usr/bin/python3 - "$html" "$(dirname "$0")/../python/report_layout.js" "$tmp/layout.html" <<'PY'
import sys
page, js, out = sys.argv[1:4]
html = open(page, encoding="utf-8").read()
script = "<script>" + open(js, encoding="utf-8").read() + "</script>"
open(out, "w", encoding="utf-8").write(html.replace("</body>", script + "</body>"))
PY
  timeout 180 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$tmp/profile2" --window-size=1400,1000 \
    --dump-dom "file://$tmp/layout.html" >"$tmp/layout-dom.html" 2>/dev/null
  /usr/bin/python3 - "$tmp/layout-dom.html" <<'PY' || fail=1
import html, json, re, sys
dom = open(sys.argv[1], encoding="utf-8").read()
m = (re.findall(r'<pre id="karst-layout">(\{.*?\})</pre>', dom, re.S) or [None])[-1]
if not m:
    print("FAIL: the layout check did not run in the page"); sys.exit(1)
r = json.loads(html.unescape(m))
bad = 0
for key, what in (("thin", "bars narrower or lower than 2 px"), ("unfilled", "unfilled bars"),
                  ("overlaps", "overlapping text boxes"), ("clipped", "texts cut off by their plot's edge"),
                  ("on_data", "texts over data marks"), ("unitless", "plots without a unit")):
    if r[key]:
        bad = 1
        print("FAIL: %d %s:" % (len(r[key]), what))
        for item in r[key][:20]:
            print("   ", item)
print("%s: %d plots, %d bars all >= 2 px and filled, %d text boxes, none overlapping another "
      "or the data, every axis with a unit" % ("ok" if not bad else "measured", r["plots"],
                                               r["bars"], r["texts"]))
sys.exit(bad)
PY
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
# Plots: a histogram per metric that varies over the members (the others are a table of
# values), the rose, the stereonet, the degree distribution, 4 views of each of 2 members and
# 4 of the survey when it has its own frame.
nvary=$(/usr/bin/python3 - "$out/ens/metrics.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))
cols = list(zip(*rows[1:]))[2:]
print(sum(1 for c in cols if len({v for v in c if v not in ("", "nan")}) > 1))
PY
)
own=0
grep -q "its own row of views" "$out/report.html" && own=4
check_report "$out/report.html" $((nvary + 3 + 2 * 4 + own)) || exit 1
# Relative, normalised paths: no text of the page (tables, plots, notes) names a file by an
# absolute path, or with "." or a ".." after a name.
/usr/bin/python3 - "$out/report.html" <<'PY' || exit 1
import html.parser, re, sys
class Text(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.words = []
    def handle_data(self, data):
        self.words += data.split()
t = Text()
t.feed(open(sys.argv[1], encoding="utf-8").read())
# a path: a word with a slash between names ("a/b", "/a", "../a"), not a lone "/" or "//"
paths = [w.strip("(),;:") for w in t.words if re.search(r"/[\w.-]", w)]
bad = [w for w in paths if w.startswith("/") or re.search(r"(^|/)\.(/|$)", w)
       or re.search(r"[^./]/\.\.(/|$)", w)]
if bad:
    print("FAIL: the page names files by absolute or unnormalised paths:", bad[:5])
    sys.exit(1)
PY
echo "ok: every path in the page is relative and normalised"
# The real parameters (17 key points, fracture families, horizons: each one table) are all
# shown with their values, read back independently.
/usr/bin/python3 "$SRC/tests/python/check_report_parameters.py" "$out/report.html" "$out/ens" ||
  { echo "FAIL: the parameters of the page differ from ensemble.json"; exit 1; }
n=$(grep -o '<table class="json rows">' "$out/report.html" | wc -l)
if [ "$n" -lt 3 ]; then echo "FAIL: $n one-table arrays, expected at least 3"; exit 1; fi
echo "ok: $n arrays of same-keyed objects shown as one table each"
