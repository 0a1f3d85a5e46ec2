#!/usr/bin/env python3
"""The same mesh in every form mtled reads gives the same answer.

Two meshes of the unit cube (scaled to 10 mm), each saved in many forms (tests/data/meshes/README.md says by
what): the two-box cube (12 nodes) in 19 forms and Gmsh's mesh of it (23 nodes) in 7. Each is compressed by
10% between its bottom and top faces, selected by coordinates so that formats without node sets take part,
for a fixed number of central-difference steps. Every run's displacement, matched by reference position,
must equal the run from the ASCII .msh file to round-off: the formats differ only in the numbering of nodes
and tets, which changes the order of floating-point sums (relative 1e-15 per operation; 1e-10 of the largest
displacement allowed after some hundred steps).

Usage: same_answer_every_format.py MTLED_EXECUTABLE FIXTURE_FOLDER SCRATCH_FOLDER
"""
import json
import os
import subprocess
import sys

import meshio
import numpy as np

TWO_BOX = {  # file: mesh block (besides type and path)
    "cube_msh22.msh": {}, "cube_msh41.msh": {}, "cube_msh22_bin.msh": {}, "cube_msh41_bin.msh": {},
    "cube.vtk": {}, "cube_v51.vtk": {}, "cube_slicer.vtk": {}, "cube_vtk_binary51.vtk": {}, "cube_meshio.vtk": {},
    "cube.vtu": {}, "cube_binary.vtu": {}, "cube_appended.vtu": {}, "cube_raw.vtu": {}, "cube_bigendian.vtu": {},
    "cube_vtk_zlib.vtu": {}, "cube_vtk_zlib_raw.vtu": {}, "cube_vtk_zlib_inline.vtu": {}, "cube_slicer.vtu": {},
    "cube_meshio.vtu": {}, "cube.inp": {},
}
GMSH_CUBE = {
    "cube_gmsh41.msh": {}, "cube_gmsh22.msh": {}, "cube_gmsh41_all.msh": {}, "cube_gmsh22_bin.msh": {},
    "cube_gmsh41_bin.msh": {}, "cube_gmsh.vtk": {}, "cube_gmsh.inp": {},
}
READER = {".msh": "gmsh_file", ".vtk": "vtk_file", ".vtu": "vtk_file", ".inp": "abaqus_file"}
SCALE = 0.01
RELATIVE_TOLERANCE = 1e-10


def scene(path):
    face = lambda z: {"box": {"min": [-1, -1, z - 1e-6], "max": [1, 1, z + 1e-6]}}
    return {
        "mesh": {"type": READER[os.path.splitext(path)[1]], "path": path, "scale": SCALE},
        "shape_function": {"type": "mls"},
        "materials": [{"type": "neo_hookean", "mu": 1000, "D": 4.02684e-5}],
        "boundaries": [
            {"type": "fixed", "name": "bottom", "nodes": face(0.0)},
            {"type": "prescribed_displacement", "name": "top", "nodes": face(SCALE), "components": ["z"],
             "displacement": [0, 0, -0.1 * SCALE]}],
        # 0.15: the per-point bound on the stable step is 2.5 times too large on the 23-node Gmsh cube, whose
        # supports hold nearly every node, and the stable-step monitor's Lanczos estimate on that cloud (whose
        # stiffness is far from symmetric) moves with the order of the sums: 1.0e-4 to 2.0e-4 s across formats and
        # kernels. A step near central differences' margin (half the estimate) lets round-off decide whether the
        # monitor lowers it at step 1 (652 or 1,049 steps at 0.3, 978 or 986 at 0.2). At 0.15 the step (3.8e-5 s) is
        # under half of the lowest estimate on every format; not a question of formats.
        "integrator": {"type": "central_difference", "duration": 0.05, "time_step_factor": 0.15},
    }


def displacement_by_position(mtled, fixtures, scratch, file):
    folder = os.path.join(scratch, file.replace(".", "_"))
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "scene.json"), "w") as f:
        json.dump(scene(os.path.join(fixtures, file)), f)
    run = subprocess.run([mtled, "run", os.path.join(folder, "scene.json"), "-o", os.path.join(folder, "out"),
                          "--threads", "1"], capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"{file}: mtled run failed ({run.returncode}):\n{run.stderr}")
    result = meshio.read(os.path.join(folder, "out", "result.vtu"))
    order = np.lexsort(np.round(result.points / 1e-12).T[::-1])
    return result.points[order], result.point_data["displacement"][order]


def main():
    mtled, fixtures, scratch = sys.argv[1:4]
    failures = 0
    for files in (TWO_BOX, GMSH_CUBE):
        names = list(files)
        points, reference = displacement_by_position(mtled, fixtures, scratch, names[0])
        largest = np.abs(reference).max()
        assert largest > 0.05 * SCALE, f"{names[0]}: the cube barely moved ({largest} m)"
        for file in names[1:]:
            p, u = displacement_by_position(mtled, fixtures, scratch, file)
            same_points = p.shape == points.shape and np.abs(p - points).max() <= 1e-12 * SCALE
            difference = np.abs(u - reference).max() / largest if same_points else float("inf")
            ok = difference <= RELATIVE_TOLERANCE
            failures += not ok
            print(f"{'ok  ' if ok else 'FAIL'} {file:28s} max |u - u({names[0]})| / max |u| = {difference:.2e}")
    if failures:
        sys.exit(f"{failures} formats gave another answer")


if __name__ == "__main__":
    main()
