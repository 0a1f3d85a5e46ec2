#!/usr/bin/env python3
"""Lists C++ function bodies longer than a limit (default 80 lines) in the given folders or files.

A function body is a brace block opened at the end of a line that looks like a definition (a closing parenthesis,
maybe followed by const/override/noexcept/an initializer list, then "{") where no function body is open: at any
namespace level (named or anonymous), in a class, in a class inside a class. Inside a body, lambdas and blocks count
towards the enclosing function. Exit status 1 when any function is over the limit, so a test can keep the layout
readable.
"""
import pathlib
import re
import sys

HEAD = re.compile(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(final)?\s*(->\s*[\w:<>, ]+)?\s*\{\s*(//.*)?$")
SKIP = re.compile(r"^\s*(if|for|while|switch|catch|else|do|return|namespace|class|struct|enum)\b")


def long_functions(path, limit):
    lines = path.read_text(errors="replace").splitlines()
    found, stack, start, name = [], [], None, ""
    for number, line in enumerate(lines, 1):
        code = re.sub(r"'(\\.|[^'\\])'", "''", re.sub(r'"(\\.|[^"\\])*"', '""', line.split("//")[0]))
        first = True
        for character in code:
            if character == "{":
                if start is None and first and HEAD.search(line) and not SKIP.match(line):
                    stack.append("function")
                    # A signature over several lines: named by the line that opens its parameter list.
                    first = number
                    while first > 1 and sum(l.count("(") - l.count(")") for l in lines[first - 1:number]) < 0:
                        first -= 1
                    start, name = number, lines[first - 1].strip()
                else:
                    stack.append("block")
                first = False
            elif character == "}" and stack:
                if stack.pop() == "function":
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
        root = pathlib.Path(folder)
        for path in [root] if root.is_file() else sorted(root.rglob("*")):
            if path.suffix in (".cpp", ".hpp", ".h", ".cu", ".cuh"):
                found += long_functions(path, limit)
    for length, where, name in sorted(found, reverse=True):
        print(f"{length:4d} lines  {where}  {name}")
    print(f"{len(found)} function(s) longer than {limit} lines in {', '.join(folders)}")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
