"""mtled's exceptions: an invalid input (where it is, what is wrong) and a numerical instability (what went wrong,
where, and the last good state)."""
import re
from typing import NamedTuple, Optional


class Problem(NamedTuple):
    """One thing wrong with the input: the file and line (when known), the JSON pointer into the scene (when the
    problem is in one), and the message with the allowed range and a suggestion."""
    file: Optional[str]
    line: Optional[int]
    pointer: Optional[str]
    message: str


def _locate(where: str):
    """(file, line, pointer) of mtled's location text: "scene.json:14: /materials/0/mu", "--set /needle/depth",
    "scene.json: /needle", "scene.json:3:7" (a JSON syntax error) or "mesh.msh:120"."""
    if where.startswith("--set "):
        return None, None, where[len("--set "):]
    match = re.fullmatch(r"(.*?):(\d+)(?::\d+)?(?:: (/.*))?", where)
    if match:
        return match[1], int(match[2]), match[3]
    match = re.fullmatch(r"(.*?): (/.*)", where)
    if match:
        return match[1], None, match[2]
    if where.startswith("/"):
        return None, None, where
    return (where or None), None, None


class Error(Exception):
    """Any error mtled reports."""


class InputError(Error, ValueError):
    """The scene (or a file it names) is invalid. `problems` lists every problem found; `pointer` and `line` are
    the first one's. Nothing was written to the run's folder."""

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = [Problem(*_locate(where), text) for where, text in problems]
        first = self.problems[0] if self.problems else Problem(None, None, None, message)
        self.pointer = first.pointer
        self.line = first.line


class InstabilityError(Error, RuntimeError):
    """The run went numerically wrong and was stopped (summary.json's status "unstable"). `diagnostic` is
    summary.json's (step, what, detail, where); `last_good_state` the (N, 3) displacement of the last good state
    (last_good_state.vtu's); `run` the run itself."""

    def __init__(self, run):
        self.run = run
        self.diagnostic = run.summary.get("diagnostic", {})
        self.last_good_state = run.displacement
        super().__init__(f"unstable at step {self.diagnostic.get('step')}: {self.diagnostic.get('what')}: "
                         f"{self.diagnostic.get('detail')}")
