#!/usr/bin/env bash
# The brain phantom's time per step against an older build, in two windows of one run: steps 1-500 (with the stable-step
# monitor's first estimate, about 60 force evaluations at step 1, and the needle's first captures) and steps 501-1000
# (the insertion under way: one force evaluation per step, the constraints refactorised as the needle captures nodes).
# Each build runs its own source tree's scene (as a user of that commit would) for 1,000 steps on 2 threads, in turn:
# this build with the CPU's best kernels, the older build, then this build with the AVX2 kernels (`--simd avx2`, the
# stand-in for an AVX2-only CPU); the windows are timed by the integrator's debug lines at steps 500 and 1000 (the
# old build prints them too), the start by the "setup" line. On a shared machine the rounds differ by 10% or more:
# quote the ratios of runs made in the same round, and their spread over rounds.
# Usage: benchmarks/brain_per_step.sh [BUILD_DIR] OLD_BUILD_DIR [ROUNDS]   (defaults: build, -, 2)
#        EXTRA="--set /mesh/target_nodes=5000" adds settings to every run (a quick try of the script itself).
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
old=${2:?usage: benchmarks/brain_per_step.sh BUILD_DIR OLD_BUILD_DIR [ROUNDS]}
rounds=${3:-2}
scene=share/scenes/needle_brain_phantom.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; instruction sets:" \
     "$(grep -o -m1 -w -e avx512f -e avx2 /proc/cpuinfo | sort -u | xargs)"
# window LABEL MTLED SCENE ARGS...: prints "LABEL ms_per_step(1-500) ms_per_step(501-1000)"
window() {
  local label=$1 mtled=$2 scene_file=$3
  shift 3
  # shellcheck disable=SC2086  # EXTRA is a list of arguments
  "$mtled" --log-level debug "$@" run "$scene_file" -o "$work/$label" --threads 2 --no-progress \
    --set /integrator/max_steps=1000 ${EXTRA:-} 2>&1 |
    python3 -u -c '
import re, sys, time
marks = {}
for line in sys.stdin:
    if re.search(r"\bsetup [0-9.]+ s", line) and "start" not in marks:
        marks["start"] = time.monotonic()
    found = re.search(r"dynamic relaxation step (500|1000):", line)
    if found:
        marks[found.group(1)] = time.monotonic()
if len(marks) < 3:
    print(sys.argv[1], "failed", "-")
else:
    first, second = marks["500"] - marks["start"], marks["1000"] - marks["500"]
    print(sys.argv[1], f"{first / 500 * 1e3:.1f}", f"{second / 500 * 1e3:.1f}")
' "$label"
}
echo
echo "| round | this build, best SIMD: ms/step 1-500 / 501-1000 | older build | this build, AVX2 | ratio best (1-500 / 501-1000) | ratio AVX2 |"
echo "| --- | --- | --- | --- | --- | --- |"
for round in $(seq 1 "$rounds"); do
  read -r _ new_first new_second < <(window new "$build/bin/mtled" "$scene")
  read -r _ old_first old_second < <(window old "$old/bin/mtled" "$(dirname "$old")/$scene")
  read -r _ avx2_first avx2_second < <(window avx2 "$build/bin/mtled" "$scene" --simd avx2)
  python3 - "$round" "$new_first" "$new_second" "$old_first" "$old_second" "$avx2_first" "$avx2_second" <<'PY'
import sys
r, *values = sys.argv[1:]
def ratio(a, b):
    try:
        return f"{float(a) / float(b):.2f}x"
    except ValueError:
        return "-"
nf, ns, of, os_, af, as_ = values
print(f"| {r} | {nf} / {ns} | {of} / {os_} | {af} / {as_} | {ratio(of, nf)} / {ratio(os_, ns)} | "
      f"{ratio(of, af)} / {ratio(os_, as_)} |")
PY
done
