#!/usr/bin/env bash
# One scene on 1 to 4 MPI ranks against one process (docs/mpi.md): the default scene, the semi-confined compression
# and the brain phantom's first 200 steps, each on 2, 3 and 4 ranks of one thread (3 and 4 oversubscribe a 2-core
# machine), compared with `mtled compare` (NRMSE) and the step count; then 2 ranks x 1 thread against 1 rank x 2
# threads (solve time). Prints one table.
#   scripts/mpi-check.sh [BUILD] [WORK]     (defaults: build, /tmp/mtled-mpi-check)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
work=${2:-/tmp/mtled-mpi-check}
mtled=$build/bin/mtled
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
rm -rf "$work" && mkdir -p "$work"
echo "# $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $(date -u +%FT%TZ), $(git rev-parse --short HEAD)"
scenes=("default share/scenes/needle_small_sample.json"
        "compression share/scenes/compression_semiconfined.json"
        "brain200 share/scenes/needle_brain_phantom.json --set /integrator/max_steps=200")
echo "| scene | ranks x threads | exit | steps | setup s | solve s | exchange s (rank 0) | NRMSE vs 1 rank (largest component) | needle force rel. diff. |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for entry in "${scenes[@]}"; do
  read -r name scene extra <<< "$entry"
  for layout in 1x1 2x1 3x1 4x1 1x2; do
    ranks=${layout%x*}; threads=${layout#*x}
    out=$work/$name-$layout
    launcher=""; [ "$ranks" -gt 1 ] && launcher="mpirun -np $ranks"
    set +e
    $launcher "$mtled" run $scene $extra -o "$out" --threads "$threads" --no-progress --log-level warn > "$out.log" 2>&1
    code=$?
    set -e
    /usr/bin/python3 - "$work/$name-1x1" "$out" "$name" "$layout" "$code" "$mtled" <<'PY'
import json, subprocess, sys, pathlib
ref, out, name, layout, code, mtled = sys.argv[1:]
s = json.load(open(pathlib.Path(out) / "summary.json"))
r = json.load(open(pathlib.Path(ref) / "summary.json"))
state = "result.vtu" if (pathlib.Path(out) / "result.vtu").exists() else "last_good_state.vtu"
nrmse, force = "-", "-"
if out != ref:
    c = subprocess.run([mtled, "compare", str(pathlib.Path(out) / state), str(pathlib.Path(ref) / state), "--json"],
                       capture_output=True, text=True)
    nrmse = "%.2e" % max(json.loads(c.stdout)["nrmse"].values())
    if "needle" in s:
        a, b = s["needle"]["final_force_N"], r["needle"]["final_force_N"]
        force = "%.1e" % (abs(a - b) / abs(b))
print(f"| {name} | {layout} | {code} | {s['steps']} | {s['setup_time_s']:.1f} | {s['solve_time_s']:.2f} | "
      f"{s['backend'].get('exchange_s', 0):.2f} | {nrmse} | {force} |")
PY
  done
done
