#!/usr/bin/python3
"""Checks the kernel's shape that docs/architecture.md describes, so that it does not grow back unseen:

- `Discretisation` and `Simulation` have at most 15 public member functions each (constructors, the destructor and
  assignment left out; each overload counts);
- the per-step record `StepRecord` has at most 10 fields and no hooks (std::function) or pointers;
- core/'s import graph has no two-way ties: no group of core's files (a header with its .cpp) that include each
  other, directly or through others;
- MPI stays inside its plugin: nothing in core/, apps/, analysis/, io/ or monitors/ includes mpi.h or tests
  MTLED_WITH_MPI, and the run command (apps/mtled/run_command.cpp) stays at most 150 lines.

Usage: kernel_shape.py SOURCE_ROOT. Prints what it counted; exit status 1 when a rule is broken.
"""
import pathlib
import re
import sys

MAX_PUBLIC_FUNCTIONS = {"Discretisation": 15, "Simulation": 15}
MAX_RECORD_FIELDS = 10
MAX_RUN_COMMAND_LINES = 150
OUTSIDE_THE_MPI_PLUGIN = ["core", "apps", "analysis", "io", "monitors"]


def without_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def class_body(text, name):
    """The text between the braces of `class name` or `struct name` (the first definition), or None."""
    match = re.search(r"\b(class|struct)\s+" + name + r"\b[^;{]*\{", text)
    if not match:
        return None
    depth, start = 1, match.end()
    for position in range(start, len(text)):
        depth += {"{": 1, "}": -1}.get(text[position], 0)
        if depth == 0:
            return match.group(1), text[start:position]
    return None


def members(kind, body):
    """(access, statement) for each statement at the class's own level: inline bodies and nested types dropped."""
    access = "public" if kind == "struct" else "private"
    statement, depth = "", 0
    for character in body:
        if character == "{":
            depth += 1
            if depth == 1:
                statement += "{}"
            continue
        if character == "}":
            depth -= 1
            if depth == 0 and re.search(r"\)[^()]*\{\}$", statement):  # an inline function's body ends it
                yield access, statement
                statement = ""
            continue
        if depth:
            continue
        statement += character
        label = re.fullmatch(r"\s*(public|private|protected)\s*:", statement)
        if label:
            access, statement = label.group(1), ""
        elif character == ";":
            yield access, statement
            statement = ""


def public_functions(text, name):
    kind, body = class_body(text, name)
    found = []
    for access, statement in members(kind, body):
        flat = " ".join(statement.split())
        if access != "public" or "(" not in flat or flat.startswith(("using ", "friend ", "struct ", "class ")):
            continue
        if re.match(r"(explicit\s+)?~?" + name + r"\s*\(", flat) or "operator=" in flat:
            continue  # construction, destruction and assignment
        found.append(flat.split("(")[0].split()[-1])
    return found


def record_fields(text, name):
    kind, body = class_body(text, name)
    return [" ".join(statement.split()) for access, statement in members(kind, body) if "(" not in statement]


def include_cycles(core):
    """Groups of core's modules (a file's stem: foo.hpp with foo.cpp) that reach each other through includes."""
    edges = {}
    for path in list(core.glob("include/mtled/**/*.hpp")) + list(core.glob("src/**/*.cpp")):
        module = path.stem
        for target in re.findall(r'#include\s+"mtled/([\w/]+)\.hpp"', path.read_text()):
            target = pathlib.PurePath(target).stem
            if target != module:
                edges.setdefault(module, set()).add(target)
    # Tarjan's strongly connected components.
    index, low, stack, on_stack, groups = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in edges.get(node, ()):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return groups


def main(root):
    root = pathlib.Path(root)
    include = root / "core/include/mtled"
    headers = {"Discretisation": "discretisation.hpp", "Simulation": "simulation.hpp"}
    failures = []
    for name, header in headers.items():
        functions = public_functions(without_comments((include / header).read_text()), name)
        print(f"{name}: {len(functions)} public functions ({', '.join(functions)})")
        if len(functions) > MAX_PUBLIC_FUNCTIONS[name]:
            failures.append(f"{name} has {len(functions)} public functions, more than {MAX_PUBLIC_FUNCTIONS[name]}: "
                            "make the new one a free function beside it, or move it to what uses it")
    fields = record_fields(without_comments((include / "monitor.hpp").read_text()), "StepRecord")
    print(f"StepRecord: {len(fields)} fields")
    if len(fields) > MAX_RECORD_FIELDS:
        failures.append(f"StepRecord has {len(fields)} fields, more than {MAX_RECORD_FIELDS}")
    for field in fields:
        if "std::function" in field or re.search(r"\*\s*\w+\s*(=.*)?$", field):
            failures.append(f"StepRecord's field \"{field}\" is a hook or a pointer: the record is plain data")
    cycles = include_cycles(root / "core")
    print(f"core's import graph: {len(cycles)} two-way ties")
    for group in cycles:
        failures.append(f"core's files {', '.join(group)} include each other")
    mpi = [str(path.relative_to(root)) for folder in OUTSIDE_THE_MPI_PLUGIN for path in (root / folder).rglob("*")
           if path.suffix in (".cpp", ".hpp", ".h", ".txt") and
           re.search(r"#\s*include\s*[<\"]mpi\.h|MTLED_WITH_MPI", path.read_text(errors="replace"))]
    print(f"outside the MPI plugin: {len(mpi)} files naming MPI")
    for path in mpi:
        failures.append(f"{path} includes mpi.h or tests MTLED_WITH_MPI: MPI belongs in plugins/backends/mpi")
    run_command = root / "apps/mtled/run_command.cpp"
    lines = len(run_command.read_text().splitlines())
    print(f"run_command.cpp: {lines} lines")
    if lines > MAX_RUN_COMMAND_LINES:
        failures.append(f"run_command.cpp has {lines} lines, more than {MAX_RUN_COMMAND_LINES}")
    for failure in failures:
        print("FAIL:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1]))
