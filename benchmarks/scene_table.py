#!/usr/bin/python3
"""The shipped scenes' figures, measured: runs every scene of share/scenes/ as a user would (`mtled run SCENE`, the
given threads) and writes the table of docs/scenes.md between its markers: nodes, integration points, steps, the
result (the needle's force at its final depth, or the reaction of the moved face or platen), the wall time and the
setup's share, with the CPU, its instruction sets and the date above it. Docs quote these figures from this table
(tests/docs/scene_figures.py fails when a doc quotes another number for the same thing).

  benchmarks/scene_table.py [--mtled build/bin/mtled] [--threads 2] [--work runs/scene-table] [--write docs/scenes.md]

needle_brain_label_map.json needs its label map, written first when missing (scripts/label_maps/write_label_map.py).
About 12 minutes on 2 cores.
"""
import argparse
import csv
import datetime
import json
import re
import subprocess
import sys
from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- scene-table:begin -->", "<!-- scene-table:end -->"

# scene file: what it is, and which reaction set is its result when it has no needle.
SCENES = {
    "needle_small_sample.json": ("the default: the paper's small sample, kinematic needle to 15 mm, coarse grid", None),
    "needle_small_sample_contact.json": ("the same with the rigid frictional-contact needle", None),
    "uniaxial_cube_ogden.json": ("10 mm Ogden cube compressed to stretch 0.8, free sides; exact solution known", "top"),
    "uniaxial_cube_neohookean.json": ("the same cube of the paper's neo-Hookean Material 4", "top"),
    "compression_semiconfined.json": ("the paper's Fig. 1 test: bonded platens, relaxed at 5, 10, 15 and 20% "
                                      "compression, the cloud graded toward the bonded rims", "top"),
    "needle_large_sample_layers.json": ("the paper's three-layer large sample (Table 2), needle to 15 mm", None),
    "needle_brain_phantom.json": ("a brain-like phantom of 0.14 x 0.156 x 0.14 m, needle to 100 mm", None),
    "needle_brain_label_map.json": ("the same phantom meshed from a 384^3 label map, needle planned as a 3D Slicer "
                                    "markups line to 100 mm", None),
}


def cpu():
    info = Path("/proc/cpuinfo").read_text()
    model = re.search(r"model name\s*:\s*(.*)", info).group(1).strip()
    family = re.search(r"cpu family\s*:\s*(\d+)", info).group(1)
    number = re.search(r"model\s*:\s*(\d+)", info).group(1)
    flags = set(re.search(r"flags\s*:\s*(.*)", info).group(1).split())
    isa = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"
    return f"{model} (family {family}, model {number}), {isa}"


def result_of(folder, reaction_set):
    summary = json.loads((folder / "summary.json").read_text())
    if reaction_set is None:
        rows = list(csv.DictReader(open(folder / "needle.csv")))
        return summary, f"{float(rows[-1]['force_N']):.4g} N at {1e3 * float(rows[-1]['depth_m']):.4g} mm"
    reactions = summary["final_reactions_N"]
    contact = reaction_set + "_contact"  # the surface that rolled onto the set's platen (its `platen` option)
    force = reactions[reaction_set][2] + reactions.get(contact, [0.0, 0.0, 0.0])[2]
    return summary, f"{abs(force):.4g} N on `{reaction_set}`" + (f" and `{contact}`" if contact in reactions else "")


def measure(mtled, scene, threads, folder):
    command = [mtled, "run", SOURCE / "share/scenes" / scene, "-o", folder, "--threads", str(threads), "--no-progress"]
    done = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{scene}: exit {done.returncode}\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return result_of(folder, SCENES[scene][1])


def row(scene, summary, result):
    wall, setup = summary["wall_time_s"], summary["setup_time_s"]
    time = f"{wall:.0f} s" if wall < 120 else f"{wall / 60:.1f} min"
    return (f"| `{scene}` | {SCENES[scene][0]} | {summary['nodes']:,} | {summary['integration_points']:,} | "
            f"{summary['steps']:,} | {result} | {time} (setup {setup:.0f} s) |")


def table(rows, threads):
    head = (f"Measured by `benchmarks/scene_table.py --threads {threads}` on {cpu()}, {threads} threads, "
            f"{datetime.date.today().isoformat()}; every run ended `ok`.\n\n"
            "| scene | what | nodes | integration points | steps | result | wall time |\n"
            "| --- | --- | --- | --- | --- | --- | --- |\n")
    return head + "\n".join(rows) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mtled", default=str(SOURCE / "build/bin/mtled"))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--work", type=Path, default=SOURCE / "runs/scene-table")
    parser.add_argument("--write", type=Path, help="the Markdown file whose marked table to replace")
    args = parser.parse_args()
    label_map = SOURCE / "share/scenes/brain.seg.nrrd"
    if not label_map.exists():
        subprocess.run([SOURCE / "scripts/label_maps/write_label_map.py", "brain", label_map, "--size", "384"],
                       check=True)
    rows = []
    for scene in SCENES:
        summary, result = measure(args.mtled, scene, args.threads, args.work / scene.removesuffix(".json"))
        rows.append(row(scene, summary, result))
        print(rows[-1], flush=True)
    text = table(rows, args.threads)
    if args.write:
        page = args.write.read_text()
        start, end = page.index(BEGIN) + len(BEGIN), page.index(END)
        args.write.write_text(page[:start] + "\n" + text + page[end:])
    else:
        print(text)


if __name__ == "__main__":
    main()
