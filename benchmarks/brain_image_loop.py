#!/usr/bin/python3
"""The image loop on the brain phantom after its needle insertion: `mtled field` and `mtled warp` on a label map, timed,
and the warped label map checked against the deformed mesh.

  brain_image_loop.py RUN IMAGE OUT [--mtled build/bin/mtled] [--markups share/scenes/needle_brain_label_map.mrk.json]

RUN is a finished run of share/scenes/needle_brain_label_map.json, IMAGE a label map of the same phantom (any size,
written by scripts/label_maps/write_label_map.py brain IMAGE --size N). Prints, as Markdown:
- the wall time of each command (2 threads unless OMP_NUM_THREADS says otherwise), from its own log;
- each region's volume: the label map's voxels before and after the warp against the mesh's tets before and after
  the run (the warped label map must follow the mesh: the ratio of the two changes within 1%);
- along the needle's path in the deformed state, how far the resampling field moves each voxel centre across the
  path: the tissue there must come from the path itself (the shaft drives the tissue along itself), within one
  voxel.
Needs numpy and VTK (Debian python3-numpy, python3-paraview).
"""
import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts" / "label_maps"))
from render_slices import placement, read_nrrd  # noqa: E402


def timed(command):
    start = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed:\n{done.stdout}{done.stderr}")
    return time.monotonic() - start, done.stdout + done.stderr


def mesh_volumes(result_vtu, deformed):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(result_vtu))
    reader.Update()
    grid = reader.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    if deformed:
        points = points + vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
    tets = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    region = vtk_to_numpy(grid.GetCellData().GetArray("region"))
    a, b, c, d = (points[tets[:, n]] for n in range(4))
    volume = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0
    return {int(r): volume[region == r].sum() for r in np.unique(region)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run")
    parser.add_argument("image")
    parser.add_argument("out")
    parser.add_argument("--mtled", default="build/bin/mtled")
    parser.add_argument("--markups", default="share/scenes/needle_brain_label_map.mrk.json")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    field_file, warped_file = out / "field.nrrd", out / "warped.seg.nrrd"
    field_s, field_log = timed([args.mtled, "field", args.run, "--like", args.image, "-o", str(field_file)])
    warp_s, warp_log = timed([args.mtled, "warp", args.image, args.run, "-o", str(warped_file)])
    print(f"| command | wall time | log |\n| --- | --- | --- |")
    for name, seconds, log in (("field", field_s, field_log), ("warp", warp_s, warp_log)):
        solved = re.search(r"solved to (\S+) m at worst; (\d+) voxels not converged", log)
        print(f"| `mtled {name}` | {seconds:.1f} s | X + u(X) = x to {solved.group(1)} m, {solved.group(2)} voxels "
              f"not converged |")

    fields, pairs, labels = read_nrrd(args.image)
    _, _, warped = read_nrrd(warped_file)
    _, origin, axes = placement(fields)
    voxel = abs(np.linalg.det(axes))  # mm^3
    names = {int(pairs[f"Segment{n}_LabelValue"]): pairs[f"Segment{n}_Name"]
             for n in range(16) if f"Segment{n}_Name" in pairs}
    result_vtu = Path(args.run) / "result.vtu"
    before, after = mesh_volumes(result_vtu, False), mesh_volumes(result_vtu, True)
    scale = 1.0 if max(before.values()) > 1.0 else 1e9  # the result in metres or millimetres
    print("\n| region | label map before | after warp | change | mesh before | after run | change | "
          "warped / deformed mesh |\n| --- | --- | --- | --- | --- | --- | --- | --- |")
    for region, label in enumerate(sorted(names)):
        v0, v1 = voxel * np.count_nonzero(labels == label), voxel * np.count_nonzero(warped == label)
        m0, m1 = scale * before[region], scale * after[region]
        print(f"| {names[label]} | {v0:.0f} mm^3 | {v1:.0f} mm^3 | {100 * (v1 / v0 - 1):+.3f}% | {m0:.0f} mm^3 | "
              f"{m1:.0f} mm^3 | {100 * (m1 / m0 - 1):+.3f}% | {100 * (v1 / m1 - 1):+.2f}% |")

    line = json.loads(Path(args.markups).read_text())["markups"][0]
    entry, target = (np.array(p["position"], float) for p in (line["controlPoints"][0], line["controlPoints"][1]))
    direction = (target - entry) / np.linalg.norm(target - entry)
    fields, _, field = read_nrrd(field_file)  # LPS, millimetres, (k, j, i, component)
    _, origin, axes = placement(fields)
    spacing = np.linalg.norm(axes, axis=0).min()
    worst, count = 0.0, 0
    to_index = np.linalg.inv(axes)
    for depth in np.arange(spacing, np.linalg.norm(target - entry), spacing):
        x = entry + depth * direction
        i, j, k = np.rint(to_index @ (x - origin)).astype(int)
        d = field[k, j, i].astype(float)
        across = np.linalg.norm(d - d.dot(direction) * direction)
        worst, count = max(worst, across), count + 1
    print(f"\nAlong the needle's path ({count} voxel centres, {spacing:.3f} mm voxels) the resampling field moves at "
          f"most {worst:.3f} mm across the path ({worst / spacing:.2f} voxels): the tissue on the path in the warped "
          f"image comes from the path")


if __name__ == "__main__":
    main()
