#!/usr/bin/env bash
# Makes `import chokeloops` work for Debian's python3 without PYTHONPATH: writes a chokeloops.pth naming
# build/python into that interpreter's user site-packages (or, with --system, its dist-packages). Nothing is
# downloaded or copied; rebuilding updates the module in place. Undo: delete the printed .pth file.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-/usr/bin/python3}
[ -f build/python/chokeloops/__init__.py ] || { echo "install-python: build first (bash scripts/build.sh)" >&2; exit 1; }
if [ "${1:-}" = "--system" ]; then
  SITE=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')  # /usr/local/lib/python3.X/dist-packages
else
  SITE=$("$PY" -m site --user-site)
fi
mkdir -p "$SITE"
echo "$PWD/build/python" > "$SITE/chokeloops.pth"
"$PY" -c 'import chokeloops; print("install-python: chokeloops", chokeloops.__version__, "from", chokeloops.__file__)'
echo "install-python: wrote $SITE/chokeloops.pth"
