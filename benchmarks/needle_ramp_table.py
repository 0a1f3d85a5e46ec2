#!/usr/bin/env python3
"""How the needle force in equilibrium depends on how fast the load is ramped (docs/validation.md).

The paper's small sample (share/scenes/needle_small_sample.json, coarse grid) is inserted to 3, 7.5 and 12 mm with
the load ramped over 400, 1,600 and 6,400 steps per 15 mm, each run relaxed at its final depth; the table gives the
force of each and its spread over the ramps at each depth. Extra --set overrides go to every run:

    benchmarks/needle_ramp_table.py --out runs/needle-ramp
    benchmarks/needle_ramp_table.py --out runs/needle-ramp-nodes --set /needle/driven=nodes_near_axis
"""
import argparse
import json
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "share/scenes/needle_small_sample.json"
DEPTHS_MM = (3.0, 7.5, 12.0)
STEPS_PER_15_MM = (400, 1600, 6400)


def run(mtled, out, depth_mm, steps_per_15, threads, overrides):
    folder = out / f"d{depth_mm:g}-s{steps_per_15}"
    args = [mtled, "run", str(SCENE), "-o", str(folder), "--threads", str(threads), "--no-progress",
            "--set", f"/needle/depth={depth_mm * 1e-3:g}",
            "--set", f"/integrator/load_steps={round(steps_per_15 * depth_mm / 15.0)}"]
    for o in overrides:
        args += ["--set", o]
    start = time.monotonic()
    with open(str(folder) + ".log", "w") as log:
        code = subprocess.run(args, stdout=log, stderr=subprocess.STDOUT).returncode
    wall = time.monotonic() - start
    if code != 0:
        raise SystemExit(f"{folder}: mtled exited with {code} (see {folder}.log)")
    summary = json.loads((folder / "summary.json").read_text())
    return summary["needle"]["final_force_N"], summary["steps"], wall


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mtled", default=str(ROOT / "build/bin/mtled"))
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    header = "| depth | " + " | ".join(f"{s:,} steps per 15 mm" for s in STEPS_PER_15_MM) + " | spread |"
    lines = [header, "| --- " * (len(STEPS_PER_15_MM) + 2) + "|"]
    for depth in DEPTHS_MM:
        forces = []
        for steps in STEPS_PER_15_MM:
            force, total_steps, wall = run(args.mtled, args.out, depth, steps, args.threads, args.overrides)
            print(f"{depth} mm, {steps} steps per 15 mm: {force:.6g} N ({total_steps} steps, {wall:.1f} s)", flush=True)
            forces.append(force)
        spread = (max(forces) - min(forces)) / forces[-1]
        lines.append(f"| {depth:g} mm | " + " | ".join(f"{f:.6g} N" for f in forces) + f" | {100 * spread:.2g}% |")
    print("\n".join(lines))
    print("\n(spread: largest minus smallest force over the slowest ramp's)")


if __name__ == "__main__":
    main()
