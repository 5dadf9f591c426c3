#!/usr/bin/env bash
# Fuzzes every input reader with libFuzzer (clang, ASan + UBSan): configures build-fuzz with
# CHOKELOOPS_FUZZ=ON (cmake/fuzz.cmake), builds the harnesses fuzz/fuzz_*.cpp and runs each for SECONDS,
# starting from the corpus kept in fuzz/corpus/NAME. Prints one line per harness:
#   fuzz NAME: N executions, 0 crashes          (or the number of findings and where they are)
# Usage: scripts/fuzz.sh [SECONDS] [NAME...]   (default 60 s, every harness)
# FUZZ_UPDATE_CORPUS=1 merges what a run found into fuzz/corpus/NAME (minimised: only inputs that add coverage).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build-fuzz}"
SECONDS_PER="${1:-60}"
shift || true
NAMES=("$@")
[ ${#NAMES[@]} -gt 0 ] || NAMES=($(cd "$ROOT/fuzz/corpus" && ls))
bash "$ROOT/scripts/install-deps.sh" fuzz >/dev/null
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Debug -DCHOKELOOPS_FUZZ=ON >"$BUILD.log" 2>&1 ||
  { tail -20 "$BUILD.log"; exit 1; }
cmake --build "$BUILD" -j"${JOBS:-2}" $(printf -- '--target fuzz_%s ' "${NAMES[@]}") >>"$BUILD.log" 2>&1 ||
  { tail -30 "$BUILD.log"; exit 1; }
status=0
for name in "${NAMES[@]}"; do
  work="$BUILD/corpus/$name" findings="$BUILD/findings/$name"
  mkdir -p "$work" "$findings"
  log="$BUILD/fuzz_$name.log"
  ASAN_OPTIONS=detect_leaks=0 "$BUILD/fuzz_$name" -max_total_time="$SECONDS_PER" -max_len=65536 -rss_limit_mb=2048 \
    -timeout=20 -print_final_stats=1 -artifact_prefix="$findings/" "$work" "$ROOT/fuzz/corpus/$name" >"$log" 2>&1 || true
  runs=$(grep -ao 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  [ -n "$runs" ] || runs=$(grep -ao '^#[0-9]*' "$log" | tail -1 | tr -d '#' || true)
  found=$(find "$findings" -type f | wc -l)
  if [ "$found" -eq 0 ]; then
    echo "fuzz $name: ${runs:-0} executions, 0 crashes"
  else
    echo "fuzz $name: ${runs:-0} executions, $found crashes (inputs in $findings, log $log)"
    status=1
  fi
  if [ "${FUZZ_UPDATE_CORPUS:-0}" = 1 ]; then
    "$BUILD/fuzz_$name" -merge=1 "$ROOT/fuzz/corpus/$name" "$work" >>"$log" 2>&1 || true
  fi
done
exit $status
