"""The Python module against the command line: the same scene gives the same files to the last bit, callbacks see the
steps asked for and can stop a run, arrays are views of mtled's memory, and errors come back as exceptions.
Run by ctest (tests/python/CMakeLists.txt) with PYTHONPATH at the build tree's package."""
import json
import os
import signal
import subprocess
from pathlib import Path

import numpy
import pytest

import mtled

SOURCE = Path(os.environ["MTLED_SOURCE_DIR"])
EXECUTABLE = os.environ["MTLED_EXECUTABLE"]
SCENES = SOURCE / "share" / "scenes"


def small_needle(deformation_coefficient=0.4):
    """The paper's small sample, coarse and short: 3 mm of insertion over 150 load steps."""
    scene = json.loads((SCENES / "needle_small_sample.json").read_text())
    scene["mesh"]["target_nodes"] = 1500
    scene["needle"]["depth"] = 0.003
    scene["needle"]["deformation_coefficient"] = deformation_coefficient
    scene["integrator"]["load_steps"] = 150
    return scene


def cli_run(scene: dict, folder: Path, threads: int) -> Path:
    """The same scene through `mtled run`, from a file."""
    folder.mkdir(parents=True)
    file = folder / "scene.json"
    file.write_text(json.dumps(scene, indent=2))
    subprocess.run([EXECUTABLE, "run", str(file), "-o", str(folder / "out"), "--threads", str(threads),
                    "--no-progress", "--log-level", "warn"], check=True)
    return folder / "out"


def vtu_displacement(file: Path) -> numpy.ndarray:
    """result.vtu's displacement as VTK (an independent reader) reads it."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(file))
    reader.Update()
    return vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("displacement"))


def same_files(a: Path, b: Path, names=("result.vtu", "needle.csv", "reactions.csv")):
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_a_scene_from_a_dict_runs_as_the_command_line_runs_its_file(tmp_path):
    scene = small_needle()
    run = mtled.run(mtled.Scene(scene, directory=SCENES), tmp_path / "python", threads=2)
    cli = cli_run(scene, tmp_path / "cli", threads=2)
    assert run.status == "ok"
    same_files(run.folder, cli)
    numpy.testing.assert_array_equal(run.displacement, vtu_displacement(cli / "result.vtu"))
    summary = json.loads((cli / "summary.json").read_text())
    assert run.summary["steps"] == summary["steps"]
    assert run.summary["needle"] == summary["needle"]
    assert run.needle["depth"][-1] == pytest.approx(0.003, rel=1e-9)
    assert run.needle["force"][-1] == pytest.approx(summary["needle"]["final_force_N"], rel=1e-9)  # 10 digits


def test_a_set_value_runs_as_the_command_lines_set(tmp_path):
    scene = mtled.Scene(small_needle(), directory=SCENES).set("/needle/deformation_coefficient", 0.25)
    run = mtled.run(scene, tmp_path / "python", threads=1)
    cli = cli_run(small_needle(0.25), tmp_path / "cli", threads=1)
    same_files(run.folder, cli)
    assert run.summary["overrides"] == ["/needle/deformation_coefficient=0.25"]


def test_a_callback_sees_every_kth_step_and_can_stop_the_run(tmp_path):
    seen = []

    def record(step):
        seen.append((step.step, step.load_fraction, step.needle["depth"], step.displacement.shape))
        assert not step.displacement.flags.writeable

    run = mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path / "all", threads=2, every=7,
                    callback=record)
    steps = run.summary["steps"]
    assert [s for s, *_ in seen] == list(range(7, steps + 1, 7))
    assert all(shape == run.nodes.shape for *_, shape in seen)
    # The needle advances with the load: depth = load fraction x 3 mm while it is being inserted.
    step, fraction, depth, _ = seen[5]
    assert depth == pytest.approx(0.003 * fraction, rel=1e-9, abs=1e-12)

    stopped = mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path / "stopped", threads=2, every=7,
                        callback=lambda step: step.step < 21)
    assert stopped.status == "stopped"
    assert stopped.summary["steps"] == 21
    assert json.loads((tmp_path / "stopped" / "summary.json").read_text())["status"] == "stopped"
    assert not (tmp_path / "stopped" / "result.vtu").exists()


def test_an_exception_in_the_callback_comes_back_as_it_was(tmp_path):
    def fail(step):
        raise LookupError(f"no such thing at step {step.step}")

    with pytest.raises(LookupError, match="no such thing at step 10"):
        mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path, threads=1, every=10, callback=fail)
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "failed"


def test_ctrl_c_stops_the_run_cleanly(tmp_path):
    def press_ctrl_c(step):
        os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path, threads=1, every=10,
                  callback=press_ctrl_c)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert summary["steps"] == 11  # the step after the one whose callback pressed it
    assert not (tmp_path / "result.vtu").exists()


def test_the_arrays_are_read_only_views_of_mtleds_memory(tmp_path):
    run = mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path, threads=2)
    for array in (run.nodes, run.displacement, run.reactions["bottom"]):
        assert not array.flags.writeable and not array.flags.owndata
        with pytest.raises(ValueError):
            array[0, 0] = 1.0
    # Two reads are two views of one buffer: nothing was copied.
    assert run.displacement.__array_interface__["data"][0] == run.displacement.__array_interface__["data"][0]
    assert numpy.shares_memory(run.displacement, run.displacement)
    # Relaxed to equilibrium, the fixed bottom holds what the needle pushes.
    assert abs(run.reactions["bottom"].sum(axis=0)[2]) == pytest.approx(abs(run.needle["force"][-1]), rel=0.05)
    # A view outlives the Run object it came from.
    u = run.displacement
    expected = numpy.array(u)
    del run
    numpy.testing.assert_array_equal(u, expected)


def test_bad_input_raises_input_error_naming_the_pointer_and_line(tmp_path):
    scene = small_needle()
    scene["materials"][0]["mu"] = -722
    text = json.dumps(scene, indent=2).splitlines()
    line = next(i for i, row in enumerate(text, 1) if '"mu": -722' in row)
    with pytest.raises(mtled.InputError) as raised:
        mtled.run(mtled.Scene(scene, directory=SCENES), tmp_path / "out")
    assert raised.value.pointer == "/materials/0/mu"
    assert raised.value.line == line
    assert not (tmp_path / "out").exists()
    problems = mtled.Scene(scene, directory=SCENES).validate()
    assert [(p.pointer, p.line) for p in problems] == [("/materials/0/mu", line)]
    assert mtled.Scene(small_needle(), directory=SCENES).validate() == []
    problems = mtled.Scene(small_needle(), directory=SCENES).set("/needle/deformation_coefficient", 1.5).validate()
    assert [(p.file, p.pointer) for p in problems] == [(None, "/needle/deformation_coefficient")]


def test_an_unstable_run_raises_instability_error_with_the_last_good_state(tmp_path):
    scene = json.loads((SCENES / "uniaxial_cube_neohookean.json").read_text())
    scene["mesh"]["target_nodes"] = 300
    scene["integrator"]["time_step_factor"] = 10.0
    scene["monitors"] = {"stable_step": "stop"}
    with pytest.raises(mtled.InstabilityError) as raised:
        mtled.run(mtled.Scene(scene, directory=SCENES), tmp_path, threads=1)
    error = raised.value
    assert error.diagnostic["what"] == "time_step_above_stable"
    assert error.last_good_state.shape == error.run.nodes.shape
    assert numpy.isfinite(error.last_good_state).all()
    assert (tmp_path / "last_good_state.vtu").exists() and not (tmp_path / "result.vtu").exists()


def test_two_runs_at_once_give_the_answers_of_two_command_line_runs(tmp_path):
    coefficients = (0.3, 0.5)
    runs = mtled.run_many([mtled.Scene(small_needle(c), directory=SCENES) for c in coefficients],
                          tmp_path / "python", threads=2)
    assert [r.folder.name for r in runs] == ["run-0", "run-1"]
    for run, c in zip(runs, coefficients):
        same_files(run.folder, cli_run(small_needle(c), tmp_path / f"cli-{c}", threads=1))
    comparison = mtled.compare(runs[0], runs[1])
    assert max(comparison["nrmse"].values()) > 0.0  # C_D changes the field


def test_compare_of_a_run_with_itself_is_zero(tmp_path):
    run = mtled.run(mtled.Scene(small_needle(), directory=SCENES), tmp_path, threads=2)
    assert mtled.compare(run, run.folder / "result.vtu")["nrmse"] == {"ux": 0.0, "uy": 0.0, "uz": 0.0}


def test_a_study_from_python_runs_mtled_for_each_configuration(tmp_path):
    """mtled.study starts each run as a child `mtled run` (the build tree's, not this Python), and its report is the
    study.json the command writes: the Ogden cube's top-face force against its exact value."""
    study = {"scene": str(SCENES / "uniaxial_cube_ogden.json"), "threads": 1, "metric": "force_error",
             "reference": {"exact_force": {"set": "top", "component": "z", "value": -0.0649565091}},
             "configurations": [{"label": f"nodes={n}", "set": {"/mesh/target_nodes": n}} for n in (300, 600)]}
    file = tmp_path / "study.json"
    file.write_text(json.dumps(study))
    report = mtled.study(file, tmp_path / "out")
    rows = report["configurations"]
    assert [r["status"] for r in rows] == ["ok", "ok"]
    # The consistent (VCI) integration of the shipped scene keeps the coarse cubes within 1% of the exact force
    # (docs/validation.md).
    assert all(r["error"] < 0.01 for r in rows), [r["error"] for r in rows]
    summary = json.loads((tmp_path / "out" / "runs" / "nodes=300" / "summary.json").read_text())
    assert summary["mtled_version"] == mtled.__version__


def test_a_fit_from_python_recovers_ogdens_mu_from_a_compression_curve(tmp_path):
    """mtled.fit as `mtled fit`: data synthesized at mu = 722 Pa with 1% noise on eight platen forces of a coarse Ogden
    cube, then mu fitted from a start 40% off (alpha held). mu is fixed by the small-strain forces: within 2% of the
    truth, and the fit converged."""
    cube = json.loads((SCENES / "uniaxial_cube_ogden.json").read_text())
    cube["mesh"]["target_nodes"] = 300
    cube["boundaries"][1]["displacement"] = [0, 0, -0.004]
    cube["integrator"] = {"type": "dynamic_relaxation", "load_steps": 300, "tolerance": 1e-7, "relaxed_increments": 8}
    (tmp_path / "cube.json").write_text(json.dumps(cube))
    (tmp_path / "forces.csv").write_text("displacement_m,force_N\n" +
                                         "".join(f"{-0.0005 * k},0\n" for k in range(1, 9)))
    fit = {"parameters": [{"name": "mu", "pointer": "/materials/0/mu", "lower": 100, "upper": 5000, "start": 722,
                           "log": True}],
           "experiments": [{"name": "compression", "scene": "cube.json", "data": "forces.csv",
                            "compare": {"type": "reaction_force", "set": "top", "component": "z"},
                            "sigma_relative": 0.01}],
           "method": {"type": "levenberg_marquardt", "max_evaluations": 20}, "threads": 2}
    (tmp_path / "fit.json").write_text(json.dumps(fit))
    made = mtled.fit(tmp_path / "fit.json", tmp_path / "truth", synthesize=1)
    [data] = made["data"]
    report = mtled.fit(tmp_path / "fit.json", tmp_path / "fit",
                       overrides=[f'/experiments/0/data="{data}"', "/parameters/0/start=433.2"])
    [mu] = report["parameters"]
    assert report["status"] == "converged", report
    assert abs(mu["value"] - 722.0) < 0.02 * 722.0, mu


def lateral_stretch(mu: float, D: float, axial: float) -> float:
    """The neo-Hookean (the paper's eq. 1 with alpha = 2) uniaxial solution's free lateral stretch: where the lateral
    nominal stress, a central difference of the energy, vanishes (bisection; scripts/uniaxial_exact.py's method)."""
    def energy(stretches):
        J = stretches[0] * stretches[1] * stretches[2]
        return mu / 2 * sum((J ** (-1 / 3) * s) ** 2 - 1 for s in stretches) + (J - 1) ** 2 / D

    def lateral_stress(s, h=1e-6):
        return (energy([s + h, s, axial]) - energy([s - h, s, axial])) / (2 * h)

    low, high = 0.5, 2.0
    for _ in range(200):
        middle = (low + high) / 2
        low, high = (low, middle) if lateral_stress(middle) > 0 else (middle, high)
    return low


def test_the_field_anywhere_is_the_exact_homogeneous_one_on_the_uniaxial_cube(tmp_path):
    """Run.field_at reads the meshless field between the nodes. The neo-Hookean cube compressed to 0.8 with free sides
    has the exact field u = ((l - 1) x, (l - 1) y, -0.2 z), l the free lateral stretch, which the moving least squares
    reproduce: at random points of the cube the displacement and F match it to 10 times the relaxation's tolerance (1e-7
    of the largest displacement, 2 mm); at the nodes the displacement is result.vtu's; outside the body NaN."""
    scene = mtled.Scene.load(SCENES / "uniaxial_cube_neohookean.json").set("/mesh/target_nodes", 300)
    run = mtled.run(scene, output=tmp_path / "cube", threads=1)
    stretches = numpy.array([lateral_stretch(1000, 4.02684e-5, 0.8)] * 2 + [0.8])
    points = numpy.random.default_rng(3).uniform(0.0, 0.01, (200, 3))
    field = run.field_at(points)
    assert field.displacement.shape == (200, 3) and field.deformation_gradient.shape == (200, 3, 3)
    numpy.testing.assert_allclose(field.displacement, points * (stretches - 1), rtol=0, atol=1e-6 * 0.002)
    numpy.testing.assert_allclose(field.deformation_gradient, numpy.broadcast_to(numpy.diag(stretches), (200, 3, 3)),
                                  rtol=0, atol=1e-6)
    at_nodes = run.field_at(run.nodes)
    numpy.testing.assert_allclose(at_nodes.displacement, vtu_displacement(run.folder / "result.vtu"), rtol=0,
                                  atol=1e-12 * 0.002)
    outside = run.field_at([[0.05, 0.05, 0.05]])
    assert numpy.isnan(outside.displacement).all() and numpy.isnan(outside.deformation_gradient).all()
    with pytest.raises(ValueError, match=r"\(n, 3\) array"):
        run.field_at([0.001, 0.002, 0.003])


def test_a_scene_loaded_by_a_relative_path_runs_after_the_script_changes_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(SOURCE)
    scene = mtled.Scene.load("share/scenes/uniaxial_cube_neohookean.json").set("/mesh/target_nodes", 300)
    monkeypatch.chdir(tmp_path)
    run = mtled.run(scene, "out", threads=1)
    assert run.summary["scene"] == str(SCENES / "uniaxial_cube_neohookean.json")
    assert (tmp_path / "out" / "result.vtu").exists()
