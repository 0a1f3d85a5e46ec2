#!/usr/bin/env bash
# Quick start, second command (and CI): install, build with tests, run the test suite (large scenes excluded).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --tests
ctest --test-dir build -j2 --output-on-failure -LE large
