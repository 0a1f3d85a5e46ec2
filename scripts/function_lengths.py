#!/usr/bin/env python3
"""Lists C++ function bodies longer than a limit (default 80 lines) in the given folders.

A function body is a brace block opened at the end of a line that looks like a definition (a closing
parenthesis, maybe followed by const/override/noexcept/an initializer list, then "{") at namespace or class
level; lambdas and blocks inside a body count towards their enclosing function. Exit status 1 when any
function is over the limit, so a test can keep the layout readable.
"""
import pathlib
import re
import sys

HEAD = re.compile(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(final)?\s*(->\s*[\w:<>, ]+)?\s*\{\s*(//.*)?$")
SKIP = re.compile(r"^\s*(if|for|while|switch|catch|else|do|return|namespace|class|struct|enum)\b")


def long_functions(path, limit):
    lines = path.read_text(errors="replace").splitlines()
    found, depth, start, name = [], 0, None, ""
    for number, line in enumerate(lines, 1):
        code = re.sub(r'"(\\.|[^"\\])*"', '""', line.split("//")[0])
        if start is None and depth <= 1 and HEAD.search(line) and not SKIP.match(line):
            start, name, body_depth = number, line.strip(), depth
        depth += code.count("{") - code.count("}")
        if start is not None and depth <= body_depth:
            if number - start + 1 > limit:
                found.append((number - start + 1, f"{path}:{start}", name[:90]))
            start = None
    return found


def main():
    limit = 80
    folders = [a for a in sys.argv[1:] if not a.startswith("--limit=")]
    for a in sys.argv[1:]:
        if a.startswith("--limit="):
            limit = int(a.split("=", 1)[1])
    found = []
    for folder in folders:
        for path in sorted(pathlib.Path(folder).rglob("*")):
            if path.suffix in (".cpp", ".hpp", ".h"):
                found += long_functions(path, limit)
    for length, where, name in sorted(found, reverse=True):
        print(f"{length:4d} lines  {where}  {name}")
    print(f"{len(found)} function(s) longer than {limit} lines in {', '.join(folders)}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
