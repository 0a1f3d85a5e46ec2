#!/usr/bin/env bash
# Installs the Debian packages (as root, or with sudo) and builds mtled in ./build (Release).
# Usage: scripts/setup.sh [--tests]   (--tests also builds the test suite)
set -euo pipefail
cd "$(dirname "$0")/.."
lists=scripts/debian-packages.txt
[ "${1:-}" = "--tests" ] && lists="$lists scripts/debian-packages-tests.txt"
packages=$(cat $lists | grep -v '^#' | xargs)
start=$SECONDS
step() { echo "== setup: $1 ($((SECONDS - start)) s so far)"; }
missing=""
for p in $packages; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  step "installing $(echo $missing | wc -w) Debian packages (a few minutes on a fresh machine)"
  sudo=""; [ "$(id -u)" = 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q $missing | { grep -E '^Setting up ' || true; }
else
  step "Debian packages already installed"
fi
tests=OFF; [ "${1:-}" = "--tests" ] && tests=ON
step "configuring (CMake)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DMTLED_BUILD_TESTS=$tests -DMTLED_BUILD_BENCHMARKS=$tests >/dev/null
step "building with 2 jobs$( [ $tests = ON ] && echo ', tests included, about 10' || echo ', about 6') minutes from scratch on 2 cores"
cmake --build build -j2
step "built"
