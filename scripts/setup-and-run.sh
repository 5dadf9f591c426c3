#!/usr/bin/env bash
# Fresh machine → install, build (Release), and run the main job on the bundled kitten:
# loops in out/kitten/ (surface.ply, loops.ply, loops.obj, loops.json, view.html) and a picture out/kitten.png.
# The Python package is made importable for this user (scripts/install-python.sh: a .pth, nothing downloaded).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
bash scripts/install-python.sh
./build/chokeloops analyze data/meshes/kitten_niagara.obj -o out/kitten --png out/kitten.png "$@"
