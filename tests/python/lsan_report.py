#!/usr/bin/python3
"""Read the sanitizer report files of a run (ASAN_OPTIONS=log_path=DIR/report) and fail on what
is karst's: any AddressSanitizer error or UBSan runtime error, and any leak whose allocation
stack has a frame in karst's code (a function karst_* or cli_*, a source file src/MODULE/*.c,
libkarst or the _karst extension). CPython and numpy leave memory unreachable at exit by design;
those leaks have no such frame and are not karst's.

Usage: lsan_report.py DIR     (exit 0 when nothing of karst's was reported)
"""
import glob
import re
import sys

OURS = re.compile(r"(\bin (karst|cli)_\w+|src/\w+/\w+\.(c|cpp)\b|libkarst|_karst\.cpython)")
files = sorted(glob.glob(sys.argv[1] + "/report*"))
found = []
for f in files:
    text = open(f, errors="replace").read()
    if "ERROR: AddressSanitizer" in text or "runtime error:" in text:
        found.append(text[:6000])
        continue
    for block in re.split(r"\n(?=(?:Direct|Indirect) leak of )", text):
        if "leak of" in block and OURS.search(block):
            found.append(block[:3000])
for b in found[:10]:
    print(b, "\n----")
print(f"sanitizer reports: {len(found)} finding(s) in karst's code ({len(files)} report file(s) read)")
sys.exit(1 if found else 0)
