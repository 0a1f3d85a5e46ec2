#!/usr/bin/env bash
# Instructions per integration-point update of a whole step (the force kernel and all per-step work), counted by
# callgrind on the default scene at about 2,000 nodes: the difference between a 120-step and a 60-step run over
# 60 steps x integration points, so setup (Gmsh, supports, shape functions) and output cancel out.
# Callgrind counts instructions, not time: the figure does not depend on the machine's load.
#
# Usage: benchmarks/instructions_per_update.sh [BUILD_DIR] [WORK_DIR]     (defaults: build, a temporary folder)
#        PRECISION=single benchmarks/instructions_per_update.sh ...           (the rows' precision; default double)
# Prints: integration points, instructions of both runs, instructions per update, then the functions that take
# the most of them (callgrind_annotate, self cost, the same difference per update).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
work=${2:-$(mktemp -d)}
mkdir -p "$work"
scene=share/scenes/needle_small_sample.json
count() {  # $1 = steps; prints the program's total instruction count
  valgrind --tool=callgrind --callgrind-out-file="$work/cg.$1" "$build/bin/mtled" run "$scene" -o "$work/run.$1" \
    --threads 1 --set /mesh/target_nodes=2000 --set /integrator/max_steps="$1" \
    --set /discretisation/precision="${PRECISION:-double}" >/dev/null 2>&1 || true
  sed -n 's/^summary: \([0-9]*\).*/\1/p' "$work/cg.$1"
}
short=$(count 60)
long=$(count 120)
points=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['integration_points'])" "$work/run.120/summary.json")
python3 - "$points" "$short" "$long" "$work" <<'PY'
import re, subprocess, sys
points, short, long_ = (int(a) for a in sys.argv[1:4])
work = sys.argv[4]
print(f"integration points {points}; instructions: 60 steps {short:,}, 120 steps {long_:,}")
print(f"instructions per integration-point update of a whole step: {(long_ - short) / (60 * points):.0f}")

def self_costs(steps):
    # callgrind_annotate's rows: "COUNT (PERCENT)  FILE:FUNCTION [OBJECT]"; the name up to its argument list.
    text = subprocess.run(["callgrind_annotate", "--inclusive=no", "--threshold=100", f"{work}/cg.{steps}"],
                          capture_output=True, text=True, check=True).stdout
    costs = {}
    for line in text.splitlines():
        row = re.match(r"\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(.*)", line)
        if not row or row.group(2).startswith("PROGRAM TOTALS"):
            continue
        name = row.group(2).split(" [", 1)[0].split(":", 1)[-1].split("(", 1)[0].strip()
        costs[name] = costs.get(name, 0) + int(row.group(1).replace(",", ""))
    return costs

before, after = self_costs(60), self_costs(120)
per_update = {name: (after.get(name, 0) - before.get(name, 0)) / (60 * points) for name in after}
print("of which (self cost per update, the largest):")
for name, cost in sorted(per_update.items(), key=lambda item: -item[1])[:12]:
    print(f"  {cost:7.1f}  {name}")
PY
