#!/usr/bin/env bash
# Builds viewer/dist/viewer.js: the viewer code and three.js (pinned in viewer/package-lock.json, from the
# npm registry) bundled by esbuild into one IIFE, which cmake/viewer.cmake compiles into the library.
# Installs viewer/node_modules with `npm ci` when it is missing or older than the lockfile
# (the test scripts in viewer/tests/ use playwright-core and pngjs from there too).
set -euo pipefail
cd "$(dirname "$0")/../viewer"
command -v npm >/dev/null || { echo "build-viewer: npm not found (install Node.js 18+ and npm)" >&2; exit 1; }
if [ ! -f node_modules/.package-lock.json ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  npm ci --no-audit --no-fund --loglevel=error
fi
mkdir -p dist
npx --no-install esbuild src/main.js --bundle --format=iife --minify --target=es2020 \
  --legal-comments=eof --log-level=warning --outfile=dist/viewer.js.tmp
mv dist/viewer.js.tmp dist/viewer.js
echo "build-viewer: wrote viewer/dist/viewer.js ($(wc -c < dist/viewer.js) bytes)"
