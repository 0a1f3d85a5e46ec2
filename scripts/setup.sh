#!/usr/bin/env bash
# Installs the Debian packages (as root, or with sudo) and builds mtled in ./build (Release).
# Usage: scripts/setup.sh [--tests]   (--tests also builds the test suite)
set -euo pipefail
cd "$(dirname "$0")/.."
lists=scripts/debian-packages.txt
[ "${1:-}" = "--tests" ] && lists="$lists scripts/debian-packages-tests.txt"
packages=$(cat $lists | grep -v '^#' | xargs)
missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $missing >/dev/null
fi
tests=OFF; [ "${1:-}" = "--tests" ] && tests=ON
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DMTLED_BUILD_TESTS=$tests -DMTLED_BUILD_BENCHMARKS=$tests >/dev/null
cmake --build build -j2
