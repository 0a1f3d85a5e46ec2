"""ParaView itself reads what a run writes: result.vtu and series.pvd with its step files, in metres and in
millimetres, each array under the name, size and unit docs/files.md gives. Run by ParaView's Python (pvpython,
Debian python3-paraview) on the uniaxial Ogden cube, whose exact answer is known: the 10 mm cube compressed to 8 mm
moves homogeneously, u = ((l - 1) x, (l - 1) y, -0.2 z) with the lateral stretch l = 1.1153 (docs/validation.md), so
the displacement ParaView reads at every point must be that field, within the run's own accuracy (0.1% of the
largest displacement: the relaxation stops at a relative change of 1e-7, and the cube's figures in validation.md
agree with the closed form to 0.02%).

  pvpython paraview_reads_results.py MTLED SOURCE_DIR WORK_DIR
"""
import json
import sys
from pathlib import Path

from paraview import servermanager
from paraview.simple import OpenDataFile, UpdatePipeline

sys.path.insert(0, str(Path(__file__).resolve().parent))
from picture_runs import run  # noqa: E402

STRETCH = 1.1153
CELL_FIELDS = ["green_strain", "cauchy_stress", "von_mises_stress", "jacobian"]
COMPONENTS = {"displacement": 3, "region": 1, "green_strain": 9, "cauchy_stress": 9, "von_mises_stress": 1,
              "jacobian": 1}


def read(path, time=None):
    """The dataset ParaView's own reader (chosen by the file's name) gives for `path` (at `time`, for a series)."""
    reader = OpenDataFile(str(path))
    if reader is None:
        sys.exit(f"ParaView has no reader for {path}")
    UpdatePipeline(time=time, proxy=reader)
    return reader, servermanager.Fetch(reader)


def arrays(data):
    """{name: (components, tuples)} of the point and the cell arrays."""
    out = {}
    for kind, block in (("points", data.GetPointData()), ("cells", data.GetCellData())):
        for i in range(block.GetNumberOfArrays()):
            a = block.GetArray(i)
            if a is not None:
                out[(kind, a.GetName())] = (a.GetNumberOfComponents(), a.GetNumberOfTuples(), a)
    return out


def check_result(data, nodes, tets, unit, failures, label):
    """Sizes, arrays and the exact displacement of one dataset; `unit` is metres per file length."""
    if data.GetNumberOfPoints() != nodes or data.GetNumberOfCells() != tets:
        failures.append(f"{label}: {data.GetNumberOfPoints()} points and {data.GetNumberOfCells()} cells, "
                        f"expected {nodes} nodes (summary.json) and {tets} tets (result.vtu)")
    found = arrays(data)
    for kind, name in [("points", "displacement"), ("points", "region"), ("cells", "region")] + \
            [("cells", f) for f in CELL_FIELDS]:
        entry = found.get((kind, name))
        expected = nodes if kind == "points" else tets
        if entry is None or entry[0] != COMPONENTS[name] or entry[1] != expected:
            failures.append(f"{label}: {kind} array {name}: {entry[:2] if entry else 'missing'}, expected "
                            f"{COMPONENTS[name]} components x {expected}")
    displacement = found[("points", "displacement")][2]
    worst, largest = 0.0, 0.0
    for i in range(nodes):
        x, y, z = (c * unit for c in data.GetPoint(i))
        exact = ((STRETCH - 1) * x, (STRETCH - 1) * y, -0.2 * z)
        u = [c * unit for c in displacement.GetTuple3(i)]
        worst = max(worst, max(abs(a - b) for a, b in zip(u, exact)))
        largest = max(largest, max(abs(e) for e in exact))
    print(f"{label}: {nodes} points, {tets} cells, largest |u - exact| {worst:.3g} m of {largest:.3g} m")
    if not largest > 1.9e-3 or worst > 1e-3 * largest:
        failures.append(f"{label}: the displacement ParaView reads is {worst:.3g} m off the exact field "
                        f"(bound {1e-3 * largest:.3g} m)")
    return displacement


def check_run(mtled, source, folder, unit_name, failures):
    overrides = ["--set", "/output/every_steps=200", "--set", f"/output/cell_data={json.dumps(CELL_FIELDS)}"]
    if unit_name == "mm":
        overrides += ["--set", "/output/length_unit=\"mm\""]
    run([mtled, "run", source / "share/scenes/uniaxial_cube_ogden.json", "-o", folder, "--no-progress"] + overrides)
    summary = json.loads((folder / "summary.json").read_text())
    nodes = summary["nodes"]
    unit = 1e-3 if unit_name == "mm" else 1.0
    _, result = read(folder / "result.vtu")
    tets = result.GetNumberOfCells()
    final = check_result(result, nodes, tets, unit, failures, f"result.vtu ({unit_name})")
    series, _ = read(folder / "series.pvd")
    times = list(series.TimestepValues)
    steps = sorted((folder / "steps").glob("*.vtu"))
    if len(times) != len(steps) or len(times) < 3 or times[0] != 0.0:
        failures.append(f"series.pvd ({unit_name}): {len(times)} times from {times[:1]}, {len(steps)} step files")
        return
    _, last = read(folder / "series.pvd", time=times[-1])
    last_displacement = check_result(last, nodes, tets, unit, failures, f"series.pvd at t = {times[-1]} ({unit_name})")
    if any(last_displacement.GetTuple3(i) != final.GetTuple3(i) for i in range(nodes)):
        failures.append(f"series.pvd ({unit_name}): the last step is not result.vtu")


def main():
    mtled, source, work = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    work.mkdir(parents=True, exist_ok=True)
    failures = []
    for unit_name in ("m", "mm"):
        check_run(mtled, source, work / f"cube-{unit_name}", unit_name, failures)
    if failures:
        sys.exit("\n".join(failures))


if __name__ == "__main__":
    main()
