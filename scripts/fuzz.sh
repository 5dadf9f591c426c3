#!/usr/bin/env bash
# Fuzzes every input reader with libFuzzer (clang, ASan + UBSan): configures build-fuzz with
# CHOKELOOPS_FUZZ=ON (cmake/fuzz.cmake), builds the harnesses fuzz/fuzz_*.cpp (one per reader: obj ply off stl
# vdb pdb cif nii nrrd mha; and mesh_levelset, vdb_levelset for the levelset stage) and runs each for SECONDS,
# starting from the corpus kept in fuzz/corpus/NAME. Prints one line per harness:
#   fuzz NAME: N executions, 0 crashes (T s, R exec/s)   (or the number of findings and where they are)
# Usage: scripts/fuzz.sh [SECONDS] [NAME...]   (default 60 s, every harness)
# Environment:
#   FUZZ_RUNS=N          stop each harness after N executions instead (SECONDS is then only an upper bound,
#                        0 = none; e.g. FUZZ_RUNS=1000000 scripts/fuzz.sh 0 obj)
#   FUZZ_MAX_LEN=BYTES   largest input libFuzzer makes (default 8192; 65536 for vdb, with -len_control=0; what the
#                        decoding reads for mesh_levelset and vdb_levelset)
#   FUZZ_BUILD_TYPE=T    CMAKE_BUILD_TYPE of the fuzz build (default RelWithDebInfo: -O2 -g, assertions on)
#   FUZZ_UPDATE_CORPUS=1 merges what a run found into fuzz/corpus/NAME (minimised: only inputs that add coverage).
#   FUZZ_TIMEOUT=S       an input running longer than S seconds is a finding (default 20; raise it for a long run
#                        that will be paused with SIGSTOP while something else is measured: the clock runs on)
#   FUZZ_ASAN_OPTIONS=O  more ASAN_OPTIONS for the harnesses (detect_leaks=0 is always set)
#   FUZZ_FORK=N          libFuzzer's fork mode: N worker processes share one run, its executions counted together
#                        (one core each; a crash in a worker is reported as usual and ends the run)
#   FUZZ_ARGS="..."      more libFuzzer flags, e.g. -entropic=0 (mesh_levelset: 2.2x the executions a second)
#   JOBS=N               build parallelism (default 2); BUILD_DIR (default build-fuzz)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build-fuzz}"
SECONDS_PER="${1:-60}"
RUNS="${FUZZ_RUNS:--1}"
shift || true
NAMES=("$@")
[ ${#NAMES[@]} -gt 0 ] || NAMES=($(cd "$ROOT/fuzz/corpus" && ls))
bash "$ROOT/scripts/install-deps.sh" fuzz >/dev/null
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE="${FUZZ_BUILD_TYPE:-RelWithDebInfo}" -DCHOKELOOPS_FUZZ=ON >"$BUILD.log" 2>&1 ||
  { tail -20 "$BUILD.log"; exit 1; }
cmake --build "$BUILD" -j"${JOBS:-2}" $(printf -- '--target fuzz_%s ' "${NAMES[@]}") >>"$BUILD.log" 2>&1 ||
  { tail -30 "$BUILD.log"; exit 1; }
status=0
for name in "${NAMES[@]}"; do
  work="$BUILD/corpus/$name" findings="$BUILD/findings/$name"
  mkdir -p "$work" "$findings"
  log="$BUILD/fuzz_$name.log"
  max_len=8192 rss_mb=2048 extra=()
  case "$name" in
    # binary seeds of 10-33 KB: mutate them at full length from the start. Under ASan the process grows by
    # ~10 KB an input (natively it stays at 50 MB over the whole corpus, and LSan finds no leak: ASan's
    # allocator keeps what the many large, varied grids freed), ~11 GB at 1M executions
    vdb) max_len=65536; rss_mb=16384; extra=(-len_control=0) ;;
    mesh_levelset) max_len=512 ;;                   # 24 vertices and 48 faces take 290 bytes
    vdb_levelset) max_len=2565 ;;                   # 512 values of 5 bytes after a 5-byte header
  esac
  max_len="${FUZZ_MAX_LEN:-$max_len}"
  if [ -n "${FUZZ_FORK:-}" ]; then extra+=(-fork="$FUZZ_FORK"); fi
  if [ -n "${FUZZ_ARGS:-}" ]; then read -r -a more <<<"$FUZZ_ARGS"; extra+=("${more[@]}"); fi
  start=$(date +%s)
  stamp="$findings/.started"; touch "$stamp"  # findings of earlier runs stay, and are not counted again
  ASAN_OPTIONS="detect_leaks=0${FUZZ_ASAN_OPTIONS:+:$FUZZ_ASAN_OPTIONS}" "$BUILD/fuzz_$name" -max_total_time="$SECONDS_PER" -runs="$RUNS" -max_len="$max_len" \
    -rss_limit_mb="$rss_mb" "${extra[@]}" \
    -timeout="${FUZZ_TIMEOUT:-20}" -print_final_stats=1 -artifact_prefix="$findings/" "$work" "$ROOT/fuzz/corpus/$name" >"$log" 2>&1 || true
  runs=$(grep -ao 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  [ -n "$runs" ] || runs=$(grep -ao '^#[0-9]*' "$log" | tail -1 | tr -d '#' || true)
  took=$(( $(date +%s) - start ))
  timing="${took} s, $(( ${runs:-0} / (took > 0 ? took : 1) )) exec/s"
  # libFuzzer also leaves its slowest inputs there (slow-unit-*): not crashes
  found=$(find "$findings" -type f ! -name .started ! -name 'slow-unit-*' -newer "$stamp" | wc -l)
  if [ "$found" -eq 0 ]; then
    echo "fuzz $name: ${runs:-0} executions, 0 crashes ($timing)"
  else
    echo "fuzz $name: ${runs:-0} executions, $found crashes ($timing; inputs in $findings, log $log)"
    status=1
  fi
  if [ "${FUZZ_UPDATE_CORPUS:-0}" = 1 ]; then
    "$BUILD/fuzz_$name" -merge=1 "$ROOT/fuzz/corpus/$name" "$work" >>"$log" 2>&1 || true
  fi
done
exit $status
