#!/usr/bin/env bash
# Quick start, first command: install, build, run the default scene into out/default.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/bin/mtled run share/scenes/needle_small_sample.json -o out/default
