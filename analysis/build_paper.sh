#!/usr/bin/env bash
# Regenerate every table of paper/paper.md from the karst binary, then splice each table into the
# paper after its <!-- paper/tables/NAME.md --> marker (replacing what followed it before).
# Usage: analysis/build_paper.sh [KARST_BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
KARST=${1:-build/karst}
analysis/survey_metrics.sh "$KARST"
if [ -x analysis/presets_table2.sh ]; then analysis/presets_table2.sh "$KARST"; fi
analysis/presets_realism.sh "$KARST"
/usr/bin/python3 - <<'PY'
import re, pathlib
p = pathlib.Path("paper/paper.md")
text = p.read_text()
def splice(m):
    path = pathlib.Path(m.group(1))
    body = path.read_text().strip() if path.exists() else "(table not generated yet)"
    return f"<!-- {m.group(1)} -->\n\n{body}\n\n<!-- end -->"
# drop previously spliced tables, then splice afresh
text = re.sub(r"(<!-- (paper/tables/[\w.]+) -->)\n\n.*?\n\n<!-- end -->", r"\1", text, flags=re.S)
text = re.sub(r"<!-- (paper/tables/[\w.]+) -->", splice, text)
tmp = p.with_suffix(".md.tmp"); tmp.write_text(text); tmp.replace(p)
PY
echo "paper/paper.md updated"
