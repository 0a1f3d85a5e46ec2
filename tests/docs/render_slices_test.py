#!/usr/bin/python3
"""The slice pictures in docs/label-maps.md come from scripts/label_maps/render_slices.py; this runs it on real files
with a known answer. The 10 mm uniaxial cube is compressed to 8 mm (share/scenes/uniaxial_cube_ogden.json); a label
map of the cube on 0.5 mm voxels (write_label_map.py cube) is warped by the run (mtled warp). In the picture of the
slice x = 5 mm the labelled box must be 20 voxels tall before and 16 after (the exact 10 and 8 mm, within one
voxel), the warped one as wide as the exact lateral stretch says (1.115, within one voxel), and the difference panel
must mark the voxels the top face left.

  render_slices_test.py MTLED SOURCE_DIR WORK_DIR
"""
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from picture_runs import run, run_ogden_cube


def main():
    mtled, source, work = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    work.mkdir(parents=True, exist_ok=True)
    run_ogden_cube(mtled, source, work / "run")
    # 40 voxels of 0.5 mm from -4.75 mm: the labelled middle half has its faces at 0 and 10 mm, the mesh's cube.
    labels = work / "cube.nrrd"
    run([source / "scripts/label_maps/write_label_map.py", "cube", labels, "--size", "40", "--spacing", "0.5",
         "--origin", "-4.75", "-4.75", "-4.75"])
    warped = work / "warped.nrrd"
    run([mtled, "warp", labels, work / "run", "-o", warped, "--frame", "LPS"])
    picture = work / "slices.png"
    run([source / "scripts/label_maps/render_slices.py", picture, labels, warped, "--axis", "x", "--at", "5",
         "--scale", "1"])
    sheet = np.asarray(Image.open(picture).convert("RGB")).astype(int)
    assert sheet.shape == (40, 3 * 40 + 2 * 4, 3), sheet.shape
    failures = []
    for name, panel, height, width in (("before", 0, 20, 20), ("after", 1, 16, 10 * 1.1153 / 0.5)):
        pixels = sheet[:, panel * 44:panel * 44 + 40]
        labelled = pixels.sum(axis=2) > 0
        rows, columns = np.nonzero(labelled)
        tall, wide = rows.max() - rows.min() + 1, columns.max() - columns.min() + 1
        print(f"{name}: the box is {tall} voxels tall (exact {height}), {wide} wide (exact {width:.2f})")
        if abs(tall - height) > 1 or abs(wide - width) > 1:
            failures.append(f"{name}: {tall} x {wide} voxels, exact {height} x {width:.2f}")
    red = sheet[:, 88:128]
    changed = np.count_nonzero((red[..., 0] > 200) & (red[..., 1] < 60))
    # The top face moves down 4 voxels and the sides out by about 1: at least the 4 rows the top left, 20 wide.
    print(f"difference panel: {changed} voxels marked")
    if changed < 4 * 20:
        failures.append(f"the difference panel marks {changed} voxels, fewer than the 80 the top face left")
    if failures:
        sys.exit("\n".join(failures))


if __name__ == "__main__":
    main()
