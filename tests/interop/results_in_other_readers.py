#!/usr/bin/env python3
"""mtled's result files read by independent readers: meshio and VTK (Debian's python3-meshio, and the VTK of
python3-paraview).

Runs a 10 mm cube whose every node is prescribed the affine displacement u = d + G X, writing a series, once
with binary (zlib) and once with ASCII files. Each result.vtu, read by meshio and by VTK, must hold the
reference points, 4-node tets and u = d + G X at every point to round-off, and the cell field "jacobian" =
det(I + G); the series must start at time 0 with zero displacement and end with the result's state; both
formats must hold the same numbers. A mesh tagged SPACE=RAS (3D Slicer) gives a result with that tag, which
VTK reads as Slicer does.

Usage: results_in_other_readers.py MTLED_EXECUTABLE SCRATCH_FOLDER
"""
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import meshio
import numpy as np

G = np.array([[0.05, 0.02, -0.01], [0.01, -0.03, 0.02], [-0.02, 0.015, -0.08]])
D = np.array([1e-4, -2e-4, 3e-4])
# Prescribed at every node, the interpolated displacement equals d + G X up to the round-off of the
# constraint solve: 1e-12 m against displacements of about 1e-3 m.
TOLERANCE_M = 1e-12
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)
        print("FAIL:", message)


def scene(fmt, mesh):
    return {
        "mesh": mesh,
        "shape_function": {"type": "mls"},
        # The jacobian is checked to round-off: single-precision rows (the default) would round it at 1e-8.
        "discretisation": {"precision": "double"},
        "materials": [{"type": "neo_hookean", "mu": 1000, "D": 4.02684e-5}],
        "boundaries": [{"type": "prescribed_displacement", "name": "everything",
                        "nodes": {"box": {"min": [-1, -1, -1], "max": [1, 1, 1]}},
                        "displacement": D.tolist(), "gradient": G.flatten().tolist()}],
        "integrator": {"type": "dynamic_relaxation", "load_steps": 20, "tolerance": 1e-6},
        "output": {"every_steps": 7, "cell_data": ["jacobian"], "vtu_format": fmt},
    }


def run(mtled, folder, fmt, mesh):
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "scene.json"), "w") as f:
        json.dump(scene(fmt, mesh), f)
    out = os.path.join(folder, "out")
    result = subprocess.run([mtled, "run", os.path.join(folder, "scene.json"), "-o", out, "--threads", "1"],
                            capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"mtled run failed ({result.returncode}):\n{result.stdout}\n{result.stderr}")
    return out


def check_affine(points, u, label):
    error = np.abs(u - (D + points @ G.T)).max()
    check(error <= TOLERANCE_M, f"{label}: displacement differs from d + G X by {error:.3g} m")


def read_with_meshio(path, label):
    mesh = meshio.read(path)
    tets = [c for c in mesh.cells if c.type == "tetra"]
    check(len(tets) == 1 and tets[0].data.shape[1] == 4, f"{label}: meshio finds no tetra block")
    return mesh, tets[0]


def read_with_vtk(path):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    points = vtk_to_numpy(grid.GetPoints().GetData())
    u = vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
    space = grid.GetFieldData().GetAbstractArray("SPACE")
    return grid, points, u, (space.GetValue(0) if space is not None else None)


def check_run(out, fmt):
    result = os.path.join(out, "result.vtu")
    mesh, tets = read_with_meshio(result, f"{fmt} result.vtu")
    check_affine(mesh.points, mesh.point_data["displacement"], f"meshio, {fmt} result.vtu")
    jacobian = mesh.cell_data["jacobian"][0]
    expected = np.linalg.det(np.eye(3) + G)
    check(np.abs(jacobian - expected).max() <= 1e-9, f"meshio, {fmt}: jacobian {jacobian.min()}..{jacobian.max()}, "
          f"expected {expected}")
    grid, points, u, _ = read_with_vtk(result)
    check(grid.GetNumberOfCells() == len(tets.data), f"VTK, {fmt}: {grid.GetNumberOfCells()} cells")
    check_affine(points, u, f"VTK, {fmt} result.vtu")
    # The series: initial state first (time 0, no displacement), the final state last.
    series = ET.parse(os.path.join(out, "series.pvd")).getroot().find("Collection").findall("DataSet")
    times = [float(s.get("timestep")) for s in series]
    check(len(series) >= 3 and times[0] == 0.0 and times == sorted(times), f"{fmt}: series times {times}")
    first = meshio.read(os.path.join(out, series[0].get("file")))
    check(np.abs(first.point_data["displacement"]).max() == 0.0, f"{fmt}: the series' first state is displaced")
    last = meshio.read(os.path.join(out, series[-1].get("file")))
    check(np.array_equal(last.point_data["displacement"], mesh.point_data["displacement"]),
          f"{fmt}: the series' last state is not the result")
    return mesh, os.path.getsize(result)


def main():
    mtled, scratch = sys.argv[1], sys.argv[2]
    box = {"type": "box", "size": [0.01, 0.01, 0.01], "target_nodes": 300}
    binary, binary_size = check_run(run(mtled, os.path.join(scratch, "binary"), "binary", box), "binary")
    ascii_, ascii_size = check_run(run(mtled, os.path.join(scratch, "ascii"), "ascii", box), "ascii")
    check(np.array_equal(binary.points, ascii_.points) and
          np.array_equal(binary.point_data["displacement"], ascii_.point_data["displacement"]),
          "the binary and ASCII results differ")
    check(binary_size < ascii_size, f"binary result {binary_size} B is not smaller than ASCII {ascii_size} B")
    print(f"result.vtu: binary {binary_size} B, ASCII {ascii_size} B")

    # 3D Slicer's frame: a mesh tagged RAS gives a result tagged RAS.
    import vtk
    tagged = os.path.join(scratch, "ras_cube.vtu")
    source = vtk.vtkXMLUnstructuredGridReader()
    source.SetFileName(os.path.join(scratch, "binary", "out", "result.vtu"))
    source.Update()
    grid = source.GetOutput()
    field = vtk.vtkStringArray()
    field.SetName("SPACE")
    field.InsertNextValue("RAS")
    grid.GetFieldData().AddArray(field)
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetInputData(grid)
    writer.SetFileName(tagged)
    writer.Write()
    out = run(mtled, os.path.join(scratch, "ras"), "binary", {"type": "vtk_file", "path": tagged})
    _, points, u, space = read_with_vtk(os.path.join(out, "result.vtu"))
    check(space == "RAS", f"the result of a mesh tagged SPACE=RAS has SPACE {space!r}")
    check_affine(points, u, "VTK, result of the RAS-tagged mesh")

    if failures:
        sys.exit(f"{len(failures)} checks failed")
    print("all checks passed")


if __name__ == "__main__":
    main()
