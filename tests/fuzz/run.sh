#!/usr/bin/env bash
# Run every libFuzzer target of a KARST_FUZZ build for a bounded time (docs/fuzzing.md).
# Builds nothing (make fuzz configures and builds build-fuzz first).
#
#   tests/fuzz/run.sh [BUILD_DIR [TARGET...]]     BUILD_DIR defaults to build-fuzz
#
# Environment: FUZZ_SECONDS (default 20) per target, FUZZ_JOBS (default 2) targets at a time,
# FUZZ_TIMEOUT (default 10) seconds per input, FUZZ_RSS_MB (default 2048) memory limit.
#
# For each target fuzz_<name>: the corpus BUILD_DIR/corpus/<name>/ (kept between runs, so that
# it grows) is seeded from tests/fuzz/seeds/<name>/, tests/fuzz/regressions/<name>/ and the files
# of datasets/ and tests/data/ of matching extension up to 1 MiB; libFuzzer runs on it with
#   -max_total_time=$FUZZ_SECONDS -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048
# and writes any crash-*, leak-*, timeout-* or oom-* input to BUILD_DIR/crashes/<name>/ (log in
# BUILD_DIR/fuzz-logs/<name>.log). A table of executions, coverage (cov: edges, ft: features),
# corpus size and result follows. Exit status: 0 when every target ran its time without a
# finding, 1 otherwise (libFuzzer's own exit status is non-zero on a crash, leak, timeout or
# out-of-memory), 2 on a usage error.
set -uo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${1:-build-fuzz}
[ $# -gt 0 ] && shift
seconds=${FUZZ_SECONDS:-20}
jobs=${FUZZ_JOBS:-2}
timeout=${FUZZ_TIMEOUT:-10}
rss=${FUZZ_RSS_MB:-2048}

if [ ! -d "$build/tests/fuzz" ]; then
  echo "run.sh: $build/tests/fuzz not found: configure and build with -DKARST_FUZZ=ON first (make fuzz)" >&2
  exit 2
fi
build=$(cd "$build" && pwd)

# The datasets/ and tests/data/ files each target is seeded with, by extension ("" = none).
exts_of() {
  case "$1" in
    scenario) echo yaml ;;
    heightfield) echo asc ;;
    surface) echo "ts asc" ;;
    survex3d) echo 3d ;;
    therion) echo sql ;;
    pline) echo pl ;;
    vtp | vtp_check) echo vtp ;;
    json) echo json ;;
    observed | published | ensemble_table) echo csv ;;
    image) echo "pgm png" ;;
    *) echo "" ;;
  esac
}

small_files() { # EXT...: files of datasets/ and tests/data/ with these extensions, <= 1 MiB
  local e
  for e in "$@"; do
    find "$root/datasets" "$root/tests/data" -type f -name "*.$e" -size -1048577c 2>/dev/null
  done
}

seed_corpus() { # NAME CORPUS
  local name=$1 corpus=$2 f d
  mkdir -p "$corpus"
  for d in "$here/seeds/$name" "$here/regressions/$name"; do
    [ -d "$d" ] && find "$d" -maxdepth 1 -type f -exec cp -n -t "$corpus" {} +
  done
  # shellcheck disable=SC2046
  for f in $(small_files $(exts_of "$name")); do
    cp -n "$f" "$corpus/$(echo "${f#"$root"/}" | tr '/' '_')"
  done
  if [ "$name" = karstnet ]; then
    # the target's input is X_nodes.dat, "\n@@links@@\n", X_links.dat (fuzz_karstnet.c)
    for f in $(find "$root/datasets" "$root/tests/data" -type f -name '*_nodes.dat' -size -1048577c); do
      local links=${f%_nodes.dat}_links.dat out
      out="$corpus/$(echo "${f#"$root"/}" | tr '/' '_').pair"
      [ -f "$links" ] && [ ! -e "$out" ] && { cat "$f"; printf '\n@@links@@\n'; cat "$links"; } >"$out"
    done
  fi
}

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for p in "$build"/tests/fuzz/fuzz_*; do
    [ -x "$p" ] && [ -f "$p" ] && targets+=("$(basename "$p" | sed 's/^fuzz_//')")
  done
fi
if [ ${#targets[@]} -eq 0 ]; then
  echo "run.sh: no fuzz_<name> program in $build/tests/fuzz" >&2
  exit 2
fi

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
if [ -z "${ASAN_SYMBOLIZER_PATH:-}" ] && command -v llvm-symbolizer >/dev/null; then
  export ASAN_SYMBOLIZER_PATH=$(command -v llvm-symbolizer)
fi
logs=$build/fuzz-logs
mkdir -p "$logs"

run_one() { # NAME: fuzz it, leave the exit status in $logs/NAME.rc
  local name=$1 corpus=$build/corpus/$1 crashes=$build/crashes/$1
  seed_corpus "$name" "$corpus"
  mkdir -p "$crashes"
  "$build/tests/fuzz/fuzz_$name" -max_total_time="$seconds" -timeout="$timeout" \
    -rss_limit_mb="$rss" -malloc_limit_mb="$rss" -print_final_stats=1 \
    -artifact_prefix="$crashes/" "$corpus" >"$logs/$name.log" 2>&1
  echo $? >"$logs/$name.rc"
}

echo "run.sh: ${#targets[@]} targets, $seconds s each, $jobs at a time (logs in $logs)"
running=0
for name in "${targets[@]}"; do
  if [ ! -x "$build/tests/fuzz/fuzz_$name" ]; then
    echo "run.sh: no $build/tests/fuzz/fuzz_$name" >&2
    echo 127 >"$logs/$name.rc"
    : >"$logs/$name.log"
    continue
  fi
  rm -f "$logs/$name.rc"
  run_one "$name" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait

status=0
printf '\n%-16s %12s %8s %8s %14s  %s\n' target execs cov ft corpus result
for name in "${targets[@]}"; do
  log=$logs/$name.log
  rc=$(cat "$logs/$name.rc" 2>/dev/null || echo 127)
  execs=$(grep -a -m1 '^stat::number_of_executed_units:' "$log" | awk '{print $2}')
  last=$(grep -a -E '^#[0-9]+.*cov: ' "$log" | tail -n 1)
  cov=$(echo "$last" | sed -n 's/.* cov: \([0-9]*\).*/\1/p')
  ft=$(echo "$last" | sed -n 's/.* ft: \([0-9]*\).*/\1/p')
  corp=$(echo "$last" | sed -n 's/.* corp: \([0-9]*\/[0-9]*[a-zA-Z]*\).*/\1/p')
  if [ "$rc" -eq 0 ]; then
    result=ok
  else
    status=1
    if grep -a -q 'ERROR: libFuzzer: out-of-memory\|ERROR: libFuzzer: malloc' "$log"; then
      result=out-of-memory
    elif grep -a -q 'ERROR: libFuzzer: timeout' "$log"; then
      result=timeout
    elif grep -a -q 'ERROR: LeakSanitizer' "$log"; then
      result=leak
    elif [ "$rc" -eq 127 ]; then
      result=missing
    else
      result="crash (exit $rc)"
    fi
  fi
  printf '%-16s %12s %8s %8s %14s  %s\n' "$name" "${execs:--}" "${cov:--}" "${ft:--}" "${corp:--}" "$result"
done

found=$(find "$build/crashes" -type f 2>/dev/null | sort)
if [ -n "$found" ]; then
  echo
  echo "run.sh: inputs that crashed, leaked, timed out or ran out of memory:"
  echo "$found" | sed 's/^/  /'
  echo "Reproduce with BUILD_DIR/tests/fuzz/fuzz_<name> FILE (log: $logs/<name>.log); once the parser"
  echo "is fixed, copy each file to tests/fuzz/regressions/<name>/ so that ctest replays it"
  echo "(fuzz_replay_<name>), and delete it from $build/crashes/."
fi
[ "$status" -eq 0 ] && echo "run.sh: all ${#targets[@]} targets ran ${seconds} s without a finding"
exit "$status"
