"""README.md's and docs/python.md's examples run as written, in order, in one namespace, from a folder that has the repository's
share/ (the paths the guide uses); then what they print and draw is checked against the physics."""
import contextlib
import io
import os
import re
from pathlib import Path

SOURCE = Path(os.environ["MTLED_SOURCE_DIR"])


def test_the_guides_examples_run_and_show_what_it_says(tmp_path, monkeypatch):
    (tmp_path / "share").symlink_to(SOURCE / "share")
    monkeypatch.chdir(tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", (SOURCE / "docs" / "python.md").read_text(), re.S)
    assert len(blocks) == 3
    printed = io.StringIO()
    namespace = {}
    with contextlib.redirect_stdout(printed):
        for block in blocks:
            exec(compile(block, "docs/python.md", "exec"), namespace)
    lines = printed.getvalue().splitlines()

    # The sweep: every run reached the scene's 15 mm, and a larger C_D drags more tissue down with the needle, so
    # the needle pushes harder.
    forces = [float(re.match(r"C_D = [\d.]+: ([\d.]+) N at 15.0 mm", line)[1]) for line in lines[:3]]
    assert forces[0] < forces[1] < forces[2], forces
    assert (tmp_path / "runs" / "cd-sweep" / "force_depth.png").stat().st_size > 10_000
    for i in range(3):
        assert (tmp_path / "runs" / "cd-sweep" / f"run-{i}" / "result.vtu").exists()

    # The callback stopped the run where the force first passed 0.05 N, on a step it was shown (every 10th).
    match = re.match(r"0.05 N reached at ([\d.]+) mm \(step (\d+)\)", lines[3])
    assert match and int(match[2]) % 10 == 0, lines[3]
    assert lines[4] == f"stopped {match[2]}"
    assert 0.0 < float(match[1]) < 15.0

    # The field beside the shaft: dragged down with the needle (u_z < 0) and sheared, both fading with the distance
    # from the axis.
    rows = [re.match(r"(\d+) mm from the axis: u_z = (-?[\d.]+) mm, E_xz = (-?[\d.]+)", line) for line in lines[5:9]]
    assert all(rows), lines[5:9]
    drags = [float(row[2]) for row in rows]
    shears = [float(row[3]) for row in rows]
    assert all(d < 0 for d in drags) and drags == sorted(drags), drags
    assert all(e > 0 for e in shears) and shears == sorted(shears, reverse=True), shears


def test_the_readmes_example_runs(tmp_path, monkeypatch):
    (tmp_path / "share").symlink_to(SOURCE / "share")
    monkeypatch.chdir(tmp_path)
    [block] = re.findall(r"```python\n(.*?)```", (SOURCE / "README.md").read_text(), re.S)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(block, "README.md", "exec"), {})
    force, shape = printed.getvalue().split(" ", 1)
    assert float(force) > 0.0
    assert re.fullmatch(r"\(\d+, 3\)", shape.strip()), shape  # (nodes, 3)
