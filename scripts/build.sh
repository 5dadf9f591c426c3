#!/usr/bin/env bash
# Installs the Debian packages (scripts/install-deps.sh) and builds chokeloops in Release into build/.
# The viewer bundle (three.js from the npm registry) is built by CMake through scripts/build-viewer.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
echo "build: ok (build/chokeloops; Python: PYTHONPATH=$PWD/build/python /usr/bin/python3 -c 'import chokeloops', or bash scripts/install-python.sh)"
