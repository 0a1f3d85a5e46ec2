#!/usr/bin/python3
"""The brain phantom's depth table: every cloud of the table in docs/stability.md inserted to 70 and 100 mm.

Each case runs `mtled run` twice (to 70 mm and to 100 mm, 20 load steps per mm) and the table gives, per case, the
nodes and integration points, the outcome at 100 mm (the depth of the first fold or J <= 0, if any), the needle
force in equilibrium at 70 and 100 mm, its deviation from the mean over the cases that reached the depth, the
smallest volume ratio of a tet outside the needle's zone and the wall time. The brain runs take minutes each; this
is a documented command, not a test:

    benchmarks/brain_depth_table.py --out runs/brain-depth                      # the shipped scenes as they are
    benchmarks/brain_depth_table.py --out runs/brain-depth-paper --drag-limit none   # the paper's unlimited drag
    benchmarks/brain_depth_table.py --out runs/brain-depth-along --refine-size 0.00135  # every cloud refined along
                                                                                        # its path to one size

Each case's spacing beside the shaft (scripts/shaft_spacing.py) comes from its mesh, written by `mtled mesh`.

The label-map cases write their label maps with scripts/label_maps/write_label_map.py into the output folder.
"""
import argparse
import csv
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
from shaft_spacing import read_inp, shaft_spacing  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
ANALYTIC = ROOT / "share/scenes/needle_brain_phantom.json"
LABEL_MAP = ROOT / "share/scenes/needle_brain_label_map.json"
STEPS_PER_MM = 20  # the shipped analytic scene's ramp: 2,000 load steps over 100 mm
SHIPPED_PATH = ([0.025, 0.006, 0.07], [0.0, 0.0, -1.0])  # both scenes' entry (m) and direction
OBLIQUE_PATH = ([-0.025, 0.006, 0.07], [0.0, 0.342, -0.940])
# --refine-size refines within this distance of the path (m), growing back over the transition, from this far
# above the entry to this far past the tip at 100 mm.
REFINE_DISTANCE, REFINE_TRANSITION, REFINE_BEYOND = 0.004, 0.008, (0.002, 0.004)


def cases(out: Path):
    """(name, scene, overrides, label-map size or None, path); the means are over the cases of the shipped path."""
    rows = [(f"analytic, target_nodes {n:,}", ANALYTIC, [f"/mesh/target_nodes={n}"], None, SHIPPED_PATH)
            for n in (60000, 66000, 74000, 82000)]
    for size in (256, 384):
        for smooth in (True, False):
            surface = "smooth" if smooth else "staircase"
            label_map = out / f"brain{size}.seg.nrrd"
            rows.append((f"label map {size}^3, {surface}", LABEL_MAP,
                         [f'/mesh/path="{label_map}"', f"/mesh/smooth={'true' if smooth else 'false'}"], size,
                         SHIPPED_PATH))
    # Not in the paper: an oblique trajectory through the left hemisphere, tilted 20 degrees forwards.
    rows.append(("analytic, left hemisphere, 20 degrees oblique (another path: not in the means)", ANALYTIC,
                 ["/needle/entry=[-0.025,0.006,0.07]", "/needle/direction=[0,0.342,-0.940]"], None, OBLIQUE_PATH))
    return rows


def refinement(path, size):
    """Overrides that refine the mesh to `size` (m) along the needle's path to 100 mm."""
    entry, direction = (np.array(v) for v in path)
    start = entry - REFINE_BEYOND[0] * direction
    end = entry + (0.1 + REFINE_BEYOND[1]) * direction
    vector = lambda v: "[" + ",".join(f"{c:.6g}" for c in v) + "]"
    return [f"/mesh/refine_from={vector(start)}", f"/mesh/refine_to={vector(end)}", f"/mesh/refine_size={size}",
            f"/mesh/refine_distance={REFINE_DISTANCE}", f"/mesh/refine_transition={REFINE_TRANSITION}"]


def spacing_by_shaft(mtled, scene, overrides, path, folder):
    """The mean edge of the tets within 5 mm of the path to 100 mm (m), from the case's mesh."""
    mesh = folder / "mesh.inp"
    if not mesh.exists():
        args = [mtled, "mesh", str(scene), "-o", str(mesh)]
        for o in overrides:
            args += ["--set", o]
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    points, tets = read_inp(mesh)
    return shaft_spacing(points, tets, np.array(path[0]), np.array(path[1]), 0.1, 0.005)[0]


def run_case(mtled, scene, overrides, depth, folder, threads, drag_limit, reuse):
    args = [mtled, "run", str(scene), "-o", str(folder), "--threads", str(threads),
            "--set", f"/needle/depth={depth}", "--set", f"/integrator/load_steps={round(STEPS_PER_MM * depth * 1e3)}"]
    if drag_limit is not None:
        args += ["--set", f"/needle/drag_limit={drag_limit}"]
    for o in overrides:
        args += ["--set", o]
    summary_file = folder / "summary.json"
    if reuse and summary_file.exists():  # a finished run (not one cut short: its status stays "running")
        summary = json.loads(summary_file.read_text())
        if summary.get("status") != "running":
            return (0 if summary.get("status") == "ok" else 3), summary.get("wall_time_s", 0.0), summary
    start = time.monotonic()
    with open(str(folder) + ".log", "w") as log:
        code = subprocess.run(args, stdout=log, stderr=subprocess.STDOUT).returncode
    wall = time.monotonic() - start
    summary = json.loads(summary_file.read_text()) if summary_file.exists() else {}
    return code, wall, summary


def describe(code, summary, depth):
    if code == 0:
        return "ok"
    reached = summary.get("needle", {}).get("final_depth_m")
    what = summary.get("diagnostic", {}).get("what") or summary.get("status", f"exit {code}")
    return f"{what} at {1e3 * reached:.1f} mm" if reached is not None else f"{what} (exit {code})"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mtled", default=str(ROOT / "build/bin/mtled"))
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--drag-limit", default="scene",
                        help="metres, 'none' (the paper's unlimited drag) or 'scene' (as the scene says)")
    parser.add_argument("--refine-size", type=float,
                        help="m: refine every cloud to this size along its path (/mesh/refine_size)")
    parser.add_argument("--only", help="comma-separated case numbers (1-based) to run")
    parser.add_argument("--reuse", action="store_true", help="keep the runs already finished in --out")
    args = parser.parse_args()
    args.out = args.out.resolve()  # the label-map cases name their map by path, which a scene takes from its folder
    args.out.mkdir(parents=True, exist_ok=True)
    drag_limit = {"scene": None, "none": "null"}.get(args.drag_limit, args.drag_limit)

    chosen = list(enumerate(cases(args.out), 1))  # a case keeps its number (and folders) when --only picks it
    if args.only:
        keep = {int(k) for k in args.only.split(",")}
        chosen = [(i, c) for i, c in chosen if i in keep]
    results = []
    for index, (name, scene, overrides, size, path) in chosen:
        if args.refine_size:
            overrides = overrides + refinement(path, args.refine_size)
        if size and not (args.out / f"brain{size}.seg.nrrd").exists():
            subprocess.run([str(ROOT / "scripts/label_maps/write_label_map.py"), "brain",  # Debian python3, numpy
                            str(args.out / f"brain{size}.seg.nrrd"), "--size", str(size)], check=True)
        row = {"case": name}
        case_folder = args.out / f"case{index}"
        case_folder.mkdir(exist_ok=True)
        row["spacing_mm"] = 1e3 * spacing_by_shaft(args.mtled, scene, overrides, path, case_folder)
        for depth in (0.07, 0.1):
            folder = args.out / f"case{index}-{round(depth * 1e3)}mm"
            code, wall, summary = run_case(args.mtled, scene, overrides, depth, folder, args.threads, drag_limit,
                                           args.reuse)
            mm = round(depth * 1e3)
            row[f"outcome_{mm}"] = describe(code, summary, depth)
            row[f"force_{mm}_N"] = summary.get("needle", {}).get("final_force_N") if code == 0 else None
            row[f"wall_{mm}_s"] = wall
            inversion = summary.get("monitors", {}).get("inversion", {})
            row[f"smallest_volume_ratio_{mm}"] = inversion.get("smallest_volume_ratio")
            row["nodes"], row["points"] = summary.get("nodes"), summary.get("integration_points")
            row[f"steps_{mm}"] = summary.get("steps")
            print(f"{name}, {mm} mm: {row[f'outcome_{mm}']}, force {row[f'force_{mm}_N']}, {wall:.0f} s", flush=True)
        results.append(row)

    with open(args.out / "table.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(results[0].keys()))
        writer.writeheader()
        writer.writerows(results)
    print(markdown(results))


def markdown(results):
    means = {}
    for mm in (70, 100):
        forces = [r[f"force_{mm}_N"] for r in results
                  if r[f"force_{mm}_N"] is not None and "another path" not in r["case"]]
        means[mm] = sum(forces) / len(forces) if forces else None

    def force(r, mm):
        f = r[f"force_{mm}_N"]
        if f is None:
            return r[f"outcome_{mm}"]
        return f"{f:.4f} N" if "another path" in r["case"] else f"{f:.4f} N ({100 * (f / means[mm] - 1):+.2f}%)"

    def ratio(r, mm):
        v = r[f"smallest_volume_ratio_{mm}"]
        return f"{v:.2g}" if v is not None else ""

    lines = ["| cloud | nodes / points | spacing by the shaft | at 100 mm | steps (70, 100 mm) | force at 70 mm | force at 100 mm | "
             "smallest volume ratio (70, 100 mm) | wall (70 + 100 mm) |", "| --- " * 9 + "|"]
    for r in results:
        nodes = f"{r['nodes']:,} / {r['points']:,}" if r["nodes"] else ""
        lines.append(f"| {r['case']} | {nodes} | {r['spacing_mm']:.2f} mm | {r['outcome_100']} | {r['steps_70']}, {r['steps_100']} | "
                     f"{force(r, 70)} | {force(r, 100)} | {ratio(r, 70)}, {ratio(r, 100)} | "
                     f"{r['wall_70_s']:.0f} + {r['wall_100_s']:.0f} s |")
    for mm in (70, 100):
        if means[mm]:
            lines.append(f"\nmean force at {mm} mm: {means[mm]:.4f} N")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
