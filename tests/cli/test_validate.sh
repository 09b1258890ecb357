#!/usr/bin/env bash
# `karst validate` on the real binary: exit codes 0 / 1 / 2 and the
# FILE:LINE:COLUMN: message format, on the shipped scenarios and the bad fixtures.
set -u
KARST=$1
SRC=$(cd "$2" && pwd)
DATA=$SRC/tests/data/scenarios
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
say() { echo "$@"; }
run() { # expected-exit description command... (stdout -> $tmp/out, stderr -> $tmp/err)
  local want=$1 what=$2; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"; local got=$?
  if [ "$got" != "$want" ]; then
    say "FAIL: $what: exit $got, expected $want"; cat "$tmp/out" "$tmp/err"; fail=1
  else
    say "ok: $what"
  fi
}
expect_err() { # exact first line of stderr
  local want=$1
  local got; got=$(head -n 1 "$tmp/err")
  if [ "$got" != "$want" ]; then say "FAIL: stderr was: $got"; say "      expected:   $want"; fail=1; fi
}

# Exit 0: the shipped scenarios validate cleanly, with a one-line summary on stdout.
run 0 "branchwork validates" "$KARST" validate "$SRC/datasets/scenarios/branchwork.yaml"
grep -q "ok: 'branchwork', domain 400 x 600 x 100 m, 12 sinks, 1 spring, 4 waypoints" "$tmp/out" \
  || { say "FAIL: branchwork summary: $(cat "$tmp/out")"; fail=1; }
[ -s "$tmp/err" ] && { say "FAIL: branchwork wrote to stderr: $(cat "$tmp/err")"; fail=1; }
run 0 "hillside (heightfield) validates" "$KARST" validate "$SRC/datasets/scenarios/hillside.yaml"
run 0 "several good files" "$KARST" validate "$DATA/good/minimal.yaml" "$DATA/good/grid.yaml"
[ "$(wc -l <"$tmp/out")" = 2 ] || { say "FAIL: expected two summary lines"; fail=1; }
# Relative paths: the heightfield is found relative to the scenario, not the working directory.
(cd "$tmp" && "$KARST" validate "$DATA/good/grid.yaml" >/dev/null 2>&1) \
  || { say "FAIL: grid.yaml from another directory"; fail=1; }
(cd "$SRC/tests/data" && "$KARST" validate scenarios/good/grid.yaml >/dev/null 2>&1) \
  || { say "FAIL: grid.yaml by a relative path"; fail=1; }

# docs/scenario.md lists every shipped scenario, and each validates.
for f in "$SRC"/datasets/scenarios/*.yaml; do
  b=$(basename "$f")
  grep -q "\`$b\`" "$SRC/docs/scenario.md" || { say "FAIL: docs/scenario.md does not list $b"; fail=1; }
  "$KARST" validate "$f" >/dev/null 2>&1 || { say "FAIL: shipped $b does not validate"; fail=1; }
done

# Exit 2: usage errors.
run 2 "no file" "$KARST" validate
run 2 "unknown option" "$KARST" validate --strict "$DATA/good/minimal.yaml"

# Exit 1: bad input, reported as FILE:LINE:COLUMN: message.
run 1 "dip out of range" "$KARST" validate "$DATA/bad/dip_range.yaml"
expect_err "$DATA/bad/dip_range.yaml:17:10: fractures[2].dip must be within [0, 90] degrees, got 135"
run 1 "misspelled enum" "$KARST" validate "$DATA/bad/enum_typo.yaml"
expect_err "$DATA/bad/enum_typo.yaml:11:22: key_points[0].type must be one of sink, spring, waypoint, got 'sinkk' (did you mean 'sink'?)"
run 1 "unknown key" "$KARST" validate "$DATA/bad/unknown_key.yaml"
expect_err "$DATA/bad/unknown_key.yaml:16:5: unknown key 'dipp' in fractures[1] (did you mean 'dip'?)"
run 1 "empty file" "$KARST" validate "$DATA/bad/empty.yaml"
expect_err "$DATA/bad/empty.yaml:1:1: the scenario file is empty (expected a map with keys such as domain, terrain and key_points; see docs/scenario.md)"
run 1 "missing file" "$KARST" validate "$tmp/none.yaml"
grep -q "none.yaml: cannot open: No such file or directory" "$tmp/err" || { say "FAIL: missing file message"; fail=1; }
run 1 "a directory" "$KARST" validate "$tmp"
expect_err "$tmp: is a directory; the scenario must be a regular file"
run 1 "/dev/zero (would never end)" "$KARST" validate /dev/zero
expect_err "/dev/zero: is a character device; the scenario must be a regular file"
mkfifo "$tmp/pipe.yaml"
run 1 "a FIFO without a writer (would block)" "$KARST" validate "$tmp/pipe.yaml"
expect_err "$tmp/pipe.yaml: is a FIFO (named pipe); the scenario must be a regular file"
run 1 "good then bad: still exit 1" "$KARST" validate "$DATA/good/minimal.yaml" "$DATA/bad/nan.yaml"
grep -q "ok: 'minimal'" "$tmp/out" || { say "FAIL: the good file was not reported"; fail=1; }

# Every bad fixture: exit 1 (not a crash), one message in the FILE:LINE:COLUMN: format.
for f in "$DATA"/bad/*.yaml; do
  "$KARST" validate "$f" >"$tmp/out" 2>"$tmp/err"; rc=$?
  if [ "$rc" != 1 ]; then say "FAIL: $(basename "$f"): exit $rc"; cat "$tmp/err"; fail=1; continue; fi
  if ! head -n 1 "$tmp/err" | grep -Eq '^[^ ]+\.(yaml|asc):[0-9]+:[0-9]+: [a-zA-Z]'; then
    say "FAIL: $(basename "$f"): message format: $(head -n 1 "$tmp/err")"; fail=1
  fi
done
[ $fail = 0 ] && say "ok: every bad fixture exits 1 with FILE:LINE:COLUMN"

# A file written on the fly: NaN given as .NaN and a key point above a flat terrain.
cat >"$tmp/inline.yaml" <<'YAML'
domain: {min: [0, 0, 0], max: [10, 10, 10]}
terrain: {elevation: 5}
key_points:
  - {type: spring, position: [5, 5, 6]}
YAML
run 1 "key point above the terrain" "$KARST" validate "$tmp/inline.yaml"
expect_err "$tmp/inline.yaml:4:5: key_points[0] 'spring1' at z = 6 m is above the terrain (5 m at x = 5, y = 5); key points must lie in the bedrock"

# The complete example in docs/scenario.md validates.
awk '/^## A complete example/{f=1;next} f&&/^```yaml/{g=1;next} g&&/^```/{exit} g' \
  "$SRC/docs/scenario.md" >"$tmp/doc_example.yaml"
run 0 "the example in docs/scenario.md" "$KARST" validate "$tmp/doc_example.yaml"
exit $fail
