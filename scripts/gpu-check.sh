#!/usr/bin/env bash
# The GPU checks and the benchmark, run from a bundle (scripts/gpu-bundle.sh) on a machine with an NVIDIA GPU:
# the GPU tests (the cuda backend against the CPU engine), then the default scene and the brain phantom (200 steps
# and the full 100 mm run) on the GPU in double and single precision and on the host's CPU cores beside them,
# and one table. Its output, with the date and the GPU, goes into docs/performance.md each time it runs on a GPU.
# Usage: gpu-check.sh BUNDLE [WORK_DIR]          (about 6 minutes on one H100 and 16 cores; CPU_FULL_RUN_LIMIT_S,
#        default 180, bounds the brain phantom's full run on the CPU, 0 leaves it out)
set -uo pipefail
bundle=$(realpath "${1:?usage: gpu-check.sh BUNDLE [WORK_DIR]}")
work=$(realpath -m "${2:-$bundle/work}")
mkdir -p "$work"
export LD_LIBRARY_PATH="$bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
mtled="$bundle/bin/mtled"
threads=$(nproc)
cpu_limit=${CPU_FULL_RUN_LIMIT_S:-180}

echo "== $(date -u +%Y-%m-%dT%H:%MZ)"
nvidia-smi --query-gpu=name,memory.total,driver_version,clocks.max.sm --format=csv,noheader 2>&1 | sed 's/^/GPU: /'
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $threads threads; $(grep -o -m1 -w 'avx512f' /proc/cpuinfo || echo 'no avx512f')"
# The GPU's memory bandwidth as a device-to-device copy moves it (bytes read + written), where PyTorch is installed.
python3 - > "$work/bandwidth.txt" 2>/dev/null <<'PY'
import torch
x = torch.empty(2 << 30, dtype=torch.uint8, device="cuda"); y = torch.empty_like(x)
for _ in range(3): y.copy_(x)
start, stop = torch.cuda.Event(enable_timing=True), torch.cuda.Event(enable_timing=True)
start.record()
for _ in range(10): y.copy_(x)
stop.record(); torch.cuda.synchronize()
print(f"{2 * 10 * x.numel() / (start.elapsed_time(stop) / 1e3) / 1e9:.0f}")
PY
echo "GPU copy bandwidth (read + write): $(cat "$work/bandwidth.txt" 2>/dev/null || echo unknown) GB/s"

echo "== GPU tests"
for test in device_layout_test cuda_backend_test; do
  MTLED_TEST_PLUGIN_DIR="$bundle/lib/mtled/plugins" MTLED_TEST_EXECUTABLE="$mtled" MTLED_TEST_BINARY_DIR="$work/tests" \
    "$bundle/tests/$test" --gtest_brief=1 2>&1 | tail -n 20
  echo "$test: exit ${PIPESTATUS[0]}"
done

# run NAME LIMIT_S SCENE ARGS...: one mtled run into $work/NAME, its exit code in $work/NAME.exit.
run() {
  local name=$1 limit=$2 scene=$3
  shift 3
  timeout "$limit" "$mtled" run "$bundle/scenes/$scene.json" -o "$work/$name" --no-progress --log-level warn "$@" \
    > "$work/$name.log" 2>&1
  echo $? > "$work/$name.exit"
  echo "$name: exit $(cat "$work/$name.exit") ($(tail -n 1 "$work/$name.log" | cut -c1-150))"
}
echo "== runs"
# Double precision is the reference the single-precision runs are compared with (single is the scenes' default).
double=(--set '/discretisation/precision="double"')
single=(--set '/discretisation/precision="single"')
run default_cpu 300 needle_small_sample --threads "$threads" "${double[@]}"
run default_gpu 300 needle_small_sample --backend cuda "${double[@]}"
run default_gpu_single 300 needle_small_sample --backend cuda "${single[@]}"
run brain200_cpu 300 needle_brain_phantom --threads "$threads" --set /integrator/max_steps=200 "${double[@]}"
run brain200_gpu 300 needle_brain_phantom --backend cuda --set /integrator/max_steps=200 "${double[@]}"
run brain_gpu 400 needle_brain_phantom --backend cuda "${double[@]}"
run brain_gpu_single 400 needle_brain_phantom --backend cuda "${single[@]}"
# The full run on the CPU takes minutes: CPU_FULL_RUN_LIMIT_S bounds it (0 leaves it out).
[ "$cpu_limit" -gt 0 ] && run brain_cpu "$cpu_limit" needle_brain_phantom --threads "$threads" "${double[@]}"

echo "== table"
python3 - "$work" "$mtled" "$(cat "$work/bandwidth.txt" 2>/dev/null || echo 0)" <<'PY'
import csv, json, os, subprocess, sys
work, mtled, bandwidth = sys.argv[1], sys.argv[2], float(sys.argv[3] or 0)
def summary(name):
    try: return json.load(open(os.path.join(work, name, "summary.json")))
    except Exception: return None
def force(name, s):
    if s and s.get("needle"): return s["needle"]["final_force_N"]
    try: return float(list(csv.DictReader(open(os.path.join(work, name, "needle_transient.csv"))))[-1]["transient_force_N"])
    except Exception: return None
def result(name, s):
    for f in ("result.vtu", "last_good_state.vtu"):
        p = os.path.join(work, name, f)
        if os.path.exists(p): return p
    return None
def nrmse(a, b):
    pa, pb = result(a, summary(a)), result(b, summary(b))
    if not pa or not pb: return None
    out = subprocess.run([mtled, "compare", pa, pb, "--json"], capture_output=True, text=True)
    return max(json.loads(out.stdout)["nrmse"].values()) if out.returncode == 0 else None
full = "brain_cpu" if summary("brain_cpu") and summary("brain_cpu").get("status") == "ok" else "brain_gpu"
rows = [("default_cpu", None), ("default_gpu", "default_cpu"), ("default_gpu_single", "default_cpu"),
        ("brain200_cpu", None), ("brain200_gpu", "brain200_cpu"), ("brain_cpu", None),
        ("brain_gpu", None if full == "brain_gpu" else full), ("brain_gpu_single", full)]
print("| run | exit | steps | setup s | solve s | wall s | M updates/s | force N | vs CPU: NRMSE, force | "
      "GPU force kernel: ms, GB/s (of copy) | host<->GPU bytes/step; host time in GPU calls | "
      "ms per step: force kernel, engine's other calls, host |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for name, reference in rows:
    s = summary(name)
    code = open(os.path.join(work, name + ".exit")).read().strip() if os.path.exists(os.path.join(work, name + ".exit")) else "-"
    if not s:
        print(f"| {name} | {code} | | | | | | | | | | |"); continue
    f = force(name, s)
    compared = ""
    if reference and summary(reference):
        e, fr = nrmse(name, reference), force(reference, summary(reference))
        rel = abs(f - fr) / abs(fr) if f is not None and fr else None
        compared = f"{e:.2e}, {rel:.2e}" if e is not None and rel is not None else "n/a"
    b = s.get("backend", {})
    kernel = ""
    if b.get("type") == "cuda" and "force_kernel_s" in b:
        share = f" ({b['force_kernel_GB_per_s'] / bandwidth:.0%})" if bandwidth > 0 else ""
        kernel = f"{1e3 * b['force_kernel_s']:.3f}, {b['force_kernel_GB_per_s']:.0f}{share}"
    traffic = (f"{b['device_to_host_bytes_per_step']:.0f} down, {b['host_to_device_bytes_per_step']:.0f} up; "
               f"in the engine {b.get('engine_calls_s', 0):.1f} s") if b.get("type") == "cuda" else ""
    # Where a step goes: the force kernel's time (events), the rest of the engine's calls (launches, copies, waits),
    # and the host's work between them (the constraint solve, the drivers, the monitors).
    per_step = ""
    if b.get("type") == "cuda" and s.get("steps") and "force_kernel_s" in b:
        steps, kernel_s = s["steps"], b["force_kernel_s"] * b.get("force_evaluations", 0)
        engine_s = b.get("engine_calls_s", 0)
        per_step = (f"{1e3 * kernel_s / steps:.3f}, {1e3 * (engine_s - kernel_s) / steps:.3f}, "
                    f"{1e3 * (s.get('solve_time_s', 0) - engine_s) / steps:.3f}")
    print(f"| {name} | {code} | {s.get('steps')} | {s.get('setup_time_s', 0):.1f} | {s.get('solve_time_s', 0):.1f} | "
          f"{s.get('wall_time_s', 0):.1f} | {s.get('ip_updates_per_s', 0) / 1e6:.1f} | "
          f"{f if f is None else f'{f:.6g}'} | {compared} | {kernel} | {traffic} | {per_step} |")
PY
