#!/usr/bin/env bash
# The speed table of docs/performance.md, measured where it runs: the CPU and its ISA, the memory bandwidth a
# copy reaches on 1 and 2 threads (the probe the kernel is measured against), then the default scene (whole run) and
# the brain phantom (first 200 steps; FULL=1 for the whole 100 mm run) on 2 threads, in single (the default) and double
# precision, and, given a second build (an older commit built in its own worktree), the same runs of it side by side.
# Per run: wall and solve time, steps, integration-point updates per second, the bytes the force kernel must move per
# update, the bandwidth it reached and its fraction of the copy's, and the floating-point operations per update
# (a count from the kernel's arithmetic: 18 per support entry for F, 18 for the forces from the stored test gradients
# of single-precision rows or 24 where double rows form them, about 450 per point for the Ogden stress and P).
# Usage: benchmarks/speed_table.sh [BUILD_DIR] [OLD_BUILD_DIR]      (defaults: build, none; the older build runs the
#        scenes of its own source tree, the folder above OLD_BUILD_DIR, as a user of that commit would)
#        SIMD=avx2 runs the new build's kernels on AVX2 (a stand-in for an AVX2-only CPU on an AVX-512 one).
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
old=${2:-}
work=$(mktemp -d)
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores; instruction sets:" \
     "$(grep -o -m1 -w -e avx512f -e avx2 /proc/cpuinfo | sort -u | xargs)"
copy() {  # $1 = threads: GB/s of a 256 MiB copy (read + write), median of 5
  "$build/bin/mtled_benchmarks" --benchmark_filter="BM_MemoryCopyThreads/threads:$1/" --benchmark_repetitions=5 \
    --benchmark_report_aggregates_only=true --benchmark_format=json 2>/dev/null |
    python3 -c "import json,sys; print(f\"{[b for b in json.load(sys.stdin)['benchmarks'] if b['aggregate_name'] == 'median'][0]['bytes_per_s'] / 1e9:.1f}\")"
}
one=$(copy 1)
two=$(copy 2)
echo "memory copy: $one GB/s on 1 thread, $two GB/s on 2 (read + write)"
steps=()
[ "${FULL:-0}" = 1 ] || steps=(--set /integrator/max_steps=200)
# run LABEL MTLED SCENE ARGS...
run() {
  local label=$1 mtled=$2 scene=$3
  shift 3
  local simd=()
  [ -n "${SIMD:-}" ] && [ "$mtled" = "$build/bin/mtled" ] && simd=(--simd "$SIMD")
  "$mtled" run "$scene" -o "$work/$label" --threads 2 --no-progress --log-level error "${simd[@]}" "$@" >/dev/null 2>&1
  python3 - "$work/$label/summary.json" "$label" "$two" <<'PY'
import json, sys
s, label, copy = json.load(open(sys.argv[1])), sys.argv[2], float(sys.argv[3])
b = s.get("backend", {})
points, mean = s["integration_points"], s.get("support_size", {}).get("mean")
per_entry = 42 if label.endswith(("-double", "-old")) else 36  # double rows (and the older build) form t
flops = f"{per_entry * mean + 450:.0f}" if mean else ""
kernel = ""
if "force_kernel_s" in b:
    per_update = b["force_kernel_bytes"] / points
    kernel = f"{per_update:.0f} | {b['force_kernel_GB_per_s']:.1f} ({b['force_kernel_GB_per_s'] / copy:.0%})"
else:
    kernel = "| "
print(f"| {label} | {s.get('simd', '')} | {s['wall_time_s']:.1f} | {s['solve_time_s']:.1f} | {s['steps']} | "
      f"{s['ip_updates_per_s'] / 1e6:.2f} | {kernel} | {flops} |")
PY
}
echo
echo "| run (2 threads) | SIMD | wall s | solve s | steps | M updates/s | kernel bytes/update | kernel GB/s (of the 2-thread copy) | flops/update |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
double=(--set '/discretisation/precision="double"')
for label_scene in "default:share/scenes/needle_small_sample.json" "brain:share/scenes/needle_brain_phantom.json"; do
  label=${label_scene%%:*}
  scene=${label_scene#*:}
  extra=()
  [ "$label" = brain ] && extra=("${steps[@]}")
  run "$label" "$build/bin/mtled" "$scene" "${extra[@]}"
  run "$label-double" "$build/bin/mtled" "$scene" "${extra[@]}" "${double[@]}"
  [ -n "$old" ] && run "$label-old" "$old/bin/mtled" "$(dirname "$old")/$scene" "${extra[@]}"
done
rm -rf "$work"
