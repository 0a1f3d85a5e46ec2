"""mtled from Python: scenes read and edited, run in this process with a callback between steps, and the results
as NumPy arrays over mtled's own memory (docs/python.md). Each call is a thin layer over what the command line does:
a run writes the folder `mtled run` writes, and gives the same numbers to the last bit."""
import concurrent.futures
import copy as _copy
import json
import os
import tempfile
import threading
from pathlib import Path
from typing import Callable, NamedTuple, Optional

import numpy

from . import _mtled
from .errors import Error, InputError, InstabilityError, Problem, _locate

__version__ = _mtled.__version__
__all__ = ["Scene", "Run", "Step", "run", "run_many", "compare", "study", "fit", "set_log_level", "Error",
           "InputError", "InstabilityError", "Problem"]

# The command line logs at "info"; a script running many scenes wants only what needs attention.
_mtled.set_log_level("warn")


def set_log_level(level: str) -> None:
    """mtled's messages on stderr: trace, debug, info, warn (the module's default), error or off."""
    _mtled.set_log_level(level)


class Scene:
    """A scene: mtled's JSON, read from a file (Scene.load) or given as a dict. Relative paths in it (meshes, images)
    are read from the file's folder, or from `directory` (default: the current folder) for a dict."""

    def __init__(self, scene: dict, name: str = "scene.json", directory=None):
        self._text = _mtled.SceneText.parse(json.dumps(scene, indent=2), name,
                                            None if directory is None else Path(directory))

    @classmethod
    def load(cls, path) -> "Scene":
        scene = cls.__new__(cls)
        scene._text = _mtled.SceneText.read(Path(path))
        return scene

    def set(self, pointer: str, value) -> "Scene":
        """Sets the value at a JSON pointer ("/needle/deformation_coefficient"), as `mtled run --set` does; returns
        the scene, so that calls chain."""
        self._text.set(pointer, json.dumps(value))
        return self

    def copy(self) -> "Scene":
        return _copy.deepcopy(self)

    def __deepcopy__(self, memo):
        scene = Scene.__new__(Scene)
        scene._text = self._text.copy()
        return scene

    def to_dict(self) -> dict:
        return json.loads(self._text.json)

    def validate(self, plugin_paths=()) -> list:
        """Every problem in the scene (a list of Problem: file, line, pointer, message); empty when it is valid. Loads
        only the plugins the scene names, as `mtled validate` does."""
        return [Problem(*_locate(where), message)
                for where, message in self._text.problems([Path(p) for p in plugin_paths])]

    def __repr__(self):
        return f"mtled.Scene({self._text.name!r})"


class Step(NamedTuple):
    """What a callback sees after a step: the step number, the time (s), the load fraction (0 to 1), the needle (a
    dict of depth (m), force (N) and phase, or None) and the displacement, an (N, 3) read-only view of mtled's memory
    valid during the call (numpy.array(step.displacement) keeps a copy)."""
    step: int
    time: float
    load_fraction: float
    needle: Optional[dict]
    displacement: numpy.ndarray


class Field(NamedTuple):
    """The displacement field at some points: `displacement` (n, 3) in m and the deformation gradient F
    `deformation_gradient` (n, 3, 3), each row NaN where no node's support covers its point."""
    displacement: numpy.ndarray
    deformation_gradient: numpy.ndarray


class Run:
    """A finished run, its folder as `mtled run` writes it. nodes, displacement and reactions are read-only NumPy views
    of mtled's memory, alive as long as the Run is."""

    def __init__(self, handle, folder: Path, scratch=None):
        self._handle = handle
        self._scratch = scratch  # a temporary folder, removed with the Run
        self.folder = folder

    @property
    def status(self) -> str:
        """summary.json's status: "ok", or "stopped" when the callback returned False."""
        return self._handle.status

    @property
    def summary(self) -> dict:
        return self._handle.summary

    @property
    def nodes(self) -> numpy.ndarray:
        """(N, 3) reference coordinates of the nodes (m)."""
        return self._handle.nodes

    @property
    def displacement(self) -> numpy.ndarray:
        """(N, 3) displacement of the nodes (m), as result.vtu holds it (last_good_state.vtu's for an unstable run)."""
        return self._handle.displacement

    @property
    def reactions(self) -> dict:
        """Each constraint set's reactions by name: (K, 3) forces (N) on its K constrained entries."""
        return self._handle.reactions

    @property
    def needle(self) -> Optional[dict]:
        """The force-depth table (needle.csv): arrays "time" (s), "depth" (m), "force" (N) and the list "phase"; None
        without a needle."""
        table = self.folder / "needle.csv"
        if not table.exists():
            return None
        rows = numpy.genfromtxt(table, delimiter=",", names=True, dtype=None, encoding="utf-8", ndmin=1)
        return {"time": numpy.asarray(rows["time_s"], dtype=float), "depth": numpy.asarray(rows["depth_m"], dtype=float),
                "force": numpy.asarray(rows["force_N"], dtype=float), "phase": [str(p) for p in rows["phase"]]}

    def field_at(self, points) -> Field:
        """The meshless displacement field of the state the run wrote (result.vtu's, or last_good_state.vtu's) at
        `points`, an (n, 3) array of reference coordinates in m (the mesh's frame): u(X) = sum_I N_I(X) u_I and
        F = I + grad u, the field itself between the nodes, not result.vtu's linear interpolation over the tets."""
        displacement, deformation_gradient = self._handle.field_at(numpy.asarray(points, dtype=float))
        return Field(displacement, deformation_gradient)

    def __repr__(self):
        return f"mtled.Run({str(self.folder)!r}, status={self.status!r})"


def run(scene: Scene, output=None, threads: Optional[int] = None, every: int = 100,
        callback: Optional[Callable[[Step], Optional[bool]]] = None, plugin_paths=()) -> Run:
    """Runs a scene in this process, as `mtled run` does, into `output` (default: a temporary folder removed with the
    Run). `callback(step)` is called after every `every`-th step; returning False stops the run (status "stopped").
    `threads`: the force loop's (default: OMP_NUM_THREADS, else every core). Raises InputError (nothing run),
    InstabilityError (the run stopped unstable) or KeyboardInterrupt (Ctrl-C, after summary.json recorded it)."""
    scratch = None
    if output is None:
        scratch = tempfile.TemporaryDirectory(prefix="mtled-run-")
        output = scratch.name
    wrapped = None if callback is None else (lambda *fields: callback(Step(*fields)))
    handle = _mtled.run(scene._text, Path(output), threads or 0, every, wrapped, [Path(p) for p in plugin_paths],
                        threading.current_thread() is threading.main_thread())
    result = Run(handle, Path(output), scratch)
    if result.status == "unstable":
        raise InstabilityError(result)
    if result.status == "interrupted":
        raise KeyboardInterrupt(f"mtled run interrupted; {result.folder / 'summary.json'} says so")
    return result


def run_many(scenes, output=None, threads: Optional[int] = None, parallel: Optional[int] = None,
             return_exceptions: bool = False, **options) -> list:
    """Runs several scenes at once in this process, the building block of a calibration or an uncertainty study: up to
    `parallel` runs at a time (default: as many as there are threads, up to the number of scenes), sharing `threads`
    (default: every core) between them. Run i writes into output/run-i (default: temporary folders). Returns the Runs
    in the order of `scenes`; when one raised, raises the first such error once all have ended, or, with
    return_exceptions, puts each error in its place. `options` go to run()."""
    scenes = list(scenes)
    total = threads or len(os.sched_getaffinity(0))
    parallel = max(1, min(parallel or total, len(scenes)))
    each = max(1, total // parallel)
    folders = [None if output is None else Path(output) / f"run-{i}" for i in range(len(scenes))]
    with concurrent.futures.ThreadPoolExecutor(max_workers=parallel) as pool:
        futures = [pool.submit(run, scene, folder, each, **options) for scene, folder in zip(scenes, folders)]
        try:
            concurrent.futures.wait(futures)
        except KeyboardInterrupt:
            _mtled.request_interrupt(True)  # every run stops at its next step, then the error goes on up
            concurrent.futures.wait(futures)
            _mtled.request_interrupt(False)
            raise
    results = []
    for future in futures:
        error = future.exception()
        if error is not None and not return_exceptions:
            raise error
        results.append(error if error is not None else future.result())
    return results


def _folder(run_or_path) -> Path:
    return run_or_path.folder if isinstance(run_or_path, Run) else Path(run_or_path)


def compare(a, b, plugin_paths=()) -> dict:
    """`mtled compare --json` of two runs (Runs, run folders or result .vtu files): NRMSE, RMSE and the largest
    difference per displacement component, B the reference."""
    return _mtled.compare(_folder(a), _folder(b), [Path(p) for p in plugin_paths])


def _report(code: int, folder: Path, report: Optional[str], command: str) -> Optional[dict]:
    if code != 0:
        raise Error(f"mtled {command} ended with exit code {code}; its log is above and its files in {folder}")
    return None if report is None else json.loads((folder / report).read_text())


def study(path, output, threads: int = 0, reuse: bool = False, log_level: str = "warn", plugin_paths=()) -> dict:
    """`mtled study` (each run a child `mtled run`): the report, study.json, as a dict."""
    code = _mtled.study(Path(path), Path(output), threads, reuse, [Path(p) for p in plugin_paths], log_level)
    return _report(code, Path(output), "study.json", "study")


def fit(path, output, overrides=(), threads: int = 0, synthesize: Optional[int] = None, log_level: str = "warn",
        plugin_paths=()) -> dict:
    """`mtled fit` (its forward runs in this process, as the command makes them): the report, fit.json, as a dict. `overrides` are --set's
    "/pointer=value" on the fit file. `synthesize=SEED` fits nothing: it makes data from the model at the start values
    with noise from that seed, as `--synthesize SEED` does, and returns {"data": [the files in output/data]}."""
    code = _mtled.fit(Path(path), Path(output), list(overrides), threads, synthesize, [Path(p) for p in plugin_paths],
                      log_level)
    if synthesize is not None:
        _report(code, Path(output), None, "fit --synthesize")
        return {"data": sorted(str(f) for f in (Path(output) / "data").iterdir())}
    return _report(code, Path(output), "fit.json", "fit")

