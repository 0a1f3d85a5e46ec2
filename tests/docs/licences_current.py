#!/usr/bin/env python3
"""docs/licences.md stays true to the build: every plugin library the build can define (each
mtled_add_plugin(... NAME name ...) in plugins/**/CMakeLists.txt, with the names a foreach() loop gives) is named in
the first column of docs/licences.md's per-binary table (the table whose first column is headed "binary"), so that
no plugin goes out without its licence stated.

Usage: licences_current.py SOURCE_DIR
"""
import pathlib
import re
import sys


def commands(text):
    """The CMake commands of a file, in order: (name, [arguments]), comments and quotes handled."""
    i, n = 0, len(text)
    while i < n:
        if text[i] == "#":  # a comment to the end of the line
            i = text.find("\n", i)
            i = n if i < 0 else i
            continue
        match = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\s*\(").match(text, i)
        if not match or (i > 0 and (text[i - 1].isalnum() or text[i - 1] == "_")):
            i += 1
            continue
        name, i, depth, arguments, word = match.group(1).lower(), match.end(), 1, [], ""
        while i < n and depth > 0:
            c = text[i]
            if c == '"':  # a quoted argument, parentheses and all
                end = i + 1
                while end < n and text[end] != '"':
                    end += 2 if text[end] == "\\" else 1
                word += text[i + 1:end]
                i = end + 1
                continue
            if c == "#":
                i = text.find("\n", i)
                i = n if i < 0 else i
                continue
            if c == "(":
                depth += 1
            elif c == ")":
                depth -= 1
            if c.isspace() or c in "()":
                if word:
                    arguments.append(word)
                word = ""
            else:
                word += c
            i += 1
        if word:
            arguments.append(word)
        yield name, arguments


def plugin_names(source):
    """{name: [files that define it]} over plugins/**/CMakeLists.txt; problems for names that cannot be resolved."""
    names, problems = {}, []
    for cmake_file in sorted((source / "plugins").rglob("CMakeLists.txt")):
        where = cmake_file.relative_to(source)
        loops = []  # the active foreach() loops: (variable, items)
        for command, arguments in commands(cmake_file.read_text()):
            if command == "foreach" and arguments:
                items = arguments[1:]
                if items[:1] == ["IN"]:
                    items = items[2:] if items[1:2] == ["ITEMS"] else None
                loops.append((arguments[0], items))
            elif command == "endforeach" and loops:
                loops.pop()
            elif command == "mtled_add_plugin":
                if "NAME" not in arguments or arguments.index("NAME") + 1 >= len(arguments):
                    problems.append(f"{where}: an mtled_add_plugin() call without a NAME")
                    continue
                name = arguments[arguments.index("NAME") + 1]
                variable = re.fullmatch(r"\$\{(\w+)\}", name)
                if not variable:
                    names.setdefault(name, []).append(str(where))
                    continue
                loop = next((items for var, items in reversed(loops) if var == variable.group(1)), None)
                if loop is None:
                    problems.append(f"{where}: mtled_add_plugin(NAME {name}): cannot tell which names {name} takes "
                                    "(only foreach(var item...) and foreach(var IN ITEMS item...) are read)")
                    continue
                for item in loop:
                    names.setdefault(item, []).append(str(where))
    return names, problems


def binary_table_cells(page):
    """The first cell of every row of the page's tables headed "binary" (header and separator rows left out)."""
    cells, in_table, wanted = [], False, False
    for line in page.read_text().splitlines():
        line = line.strip()
        if not line.startswith("|"):
            in_table = False
            continue
        first = line.strip("|").split("|")[0].strip()
        if not in_table:  # the header row
            in_table, wanted = True, first.lower() == "binary"
            continue
        if wanted and not re.fullmatch(r":?-+:?", first):
            cells.append(first)
    return cells


def main():
    source = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    page = source / "docs" / "licences.md"
    names, problems = plugin_names(source)
    if not names:
        problems.append(f"no mtled_add_plugin(... NAME ...) found under {source / 'plugins'}")
    if not page.exists():
        problems.append(f"{page} does not exist")
        cells = []
    else:
        cells = binary_table_cells(page)
        if not cells:
            problems.append("docs/licences.md: no table whose first column is headed 'binary' (the licence per binary)")
    for name in sorted(names):
        pattern = re.compile(rf"(?<![A-Za-z0-9_]){re.escape(name)}(?![A-Za-z0-9_])")
        if not any(pattern.search(cell) for cell in cells):
            problems.append(f"docs/licences.md: no row of the per-binary table names the plugin '{name}' "
                            f"(defined in {', '.join(sorted(set(names[name])))}); add a row with its licence")
    print(f"checked {len(names)} plugin names against the {len(cells)} rows of docs/licences.md's per-binary table")
    for problem in problems:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
