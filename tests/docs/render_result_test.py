#!/usr/bin/python3
"""The result pictures in docs/ come from scripts/render_result.py; this runs it on a run with a known answer. The
10 mm uniaxial cube compressed to 8 mm (share/scenes/uniaxial_cube_ogden.json) has the homogeneous displacement
u = ((l - 1) x, (l - 1) y, -0.2 z) with the lateral stretch l = 1.1153 of the exact solution (docs/validation.md),
linear, so the picture's field is exact wherever the run is. Each pixel's colour, read back through the colour bar,
must give |u| there within two colour levels (of the 256 from 0 to the largest |u|), on the reference cut and on the
deformed one (where the cube is 8 mm tall and 11.15 mm wide).

  render_result_test.py MTLED SOURCE_DIR WORK_DIR
"""
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from picture_runs import run, run_ogden_cube

STRETCH = 1.1153  # the lateral stretch of the Ogden cube at 20% compression (docs/validation.md)


def main():
    mtled, source, work = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    work.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(source / "scripts"))
    from render_result import colour_table  # noqa: E402

    run_ogden_cube(mtled, source, work / "run")
    table = colour_table().astype(int)
    failures = []
    for deformed in (False, True):
        picture = work / f"cube{'-deformed' if deformed else ''}.png"
        # 0.1 mm pixels on y = 5 mm (in the deformed cut: y = 5 l mm, the same material plane); 12 mm square.
        at = 5 * STRETCH if deformed else 5.0
        run([source / "scripts/render_result.py", work / "run", picture, "--axis", "y", "--at", at, "--pixel", "0.1"] +
            (["--deformed"] if deformed else []))
        sheet = np.asarray(Image.open(picture).convert("RGB")).astype(int)
        width = 1 + int(np.floor(10 * (STRETCH if deformed else 1) / 0.1 + 1e-6))
        height = 1 + int(np.floor((8 if deformed else 10) / 0.1 + 1e-6))
        field = sheet[10 + 14:10 + 14 + height, 10:10 + width][::-1]  # rows upwards in z
        top = np.hypot(np.hypot((STRETCH - 1) * 10, (STRETCH - 1) * 5), 2.0)
        worst = 0.0
        for j in range(2, height - 2, 5):
            for i in range(2, width - 2, 5):
                x, z = 0.1 * i, 0.1 * j
                if deformed:  # back to the reference point
                    x, z = x / STRETCH, z / 0.8
                exact = np.linalg.norm([(STRETCH - 1) * x, (STRETCH - 1) * 5, -0.2 * z])
                level = np.argmin(((table - field[j, i]) ** 2).sum(axis=1))
                worst = max(worst, abs(level - exact / top * 255))
        print(f"{picture.name}: {width} x {height} pixels, worst colour-level error {worst:.2f} (bound 2)")
        if worst > 2:
            failures.append(f"{picture.name}: a pixel's colour is {worst:.2f} levels off the exact |u|")
    if failures:
        sys.exit("\n".join(failures))


if __name__ == "__main__":
    main()
