#!/usr/bin/env bash
# The input tests under AddressSanitizer + UBSan: configures build-asan with CHOKELOOPS_SANITIZE=ON, which
# builds only the input stage (mesh/.vdb reading, repair, level set), a `chokeloops levelset` CLI and the
# input test binary, at -O1 -g (cmake/sanitize.cmake), then runs the selected tests with ctest.
# Usage: scripts/test-sanitize.sh [ctest -R regex]   (default: the bad-input suite, .vdb IO and level-set
# accuracy tests; 'BadInput|VdbIo|LevelSet' adds the manifest meshes, minutes under ASan)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${BUILD_DIR:-$ROOT/build-asan}"
JOBS="${JOBS:-2}"
REGEX="${1:-BadInput|VdbIo|LevelSetAccuracy|LevelSetVdbInput|WindingNumber}"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Debug -DCHOKELOOPS_SANITIZE=ON >/dev/null
cmake --build "$BUILD" -j"$JOBS" --target chokeloops_input_tests
cd "$BUILD"
ctest -R "$REGEX" -j"$JOBS" --output-on-failure
