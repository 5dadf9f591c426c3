#!/usr/bin/env bash
# Builds chokeloops with AddressSanitizer + UBSan (CHOKELOOPS_SANITIZE) in build-asan and runs the
# bad-input suite and the .vdb IO tests under it. Usage: scripts/test-sanitize.sh [extra gtest filter]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build-asan}"
JOBS="${JOBS:-2}"
# Debug (-O0): CGAL-heavy files take over 20 min each with -O2 + ASan + debug info on a 2-core machine
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Debug -DCHOKELOOPS_SANITIZE=ON >/dev/null
cmake --build "$BUILD" -j"$JOBS" --target chokeloops_tests chokeloops
# leak checking is off: OpenVDB/TBB keep global singletons alive at exit
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
FILTER="BadInput*:VdbIo*${1:+:$1}"
"$BUILD/tests/chokeloops_tests" --gtest_filter="$FILTER"
