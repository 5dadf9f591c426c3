#!/usr/bin/env bash
# Installs exactly the Debian 12 packages chokeloops needs to build, test and benchmark.
# Idempotent; run as root (or with sudo available). `install-deps.sh fuzz` adds clang and libFuzzer
# (scripts/fuzz.sh).
set -euo pipefail
PKGS=(
  build-essential cmake pkg-config git
  libopenvdb-dev libboost-iostreams-dev libblosc-dev libtbb-dev zlib1g-dev libimath-dev
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libeigen3-dev libtet1.5-dev
  libgtest-dev googletest libphat-dev
  nlohmann-json3-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-distributed
  gemmi-dev tao-pegtl-dev
  libnifti2-dev libteem-dev libinsighttoolkit5-dev
  chromium
)
if [ "${1:-}" = fuzz ]; then PKGS+=(clang libfuzzer-14-dev); fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "install-deps: installed ${missing[*]}"
