#!/usr/bin/env python3
"""The documentation says what is true now, for users, and never how the project was built.

Two checks, one exit status:

1. No build history: README.md, docs/*.md and the comments and test names of the source tree (core/ apps/
   analysis/ io/ monitors/ plugins/ tests/ benchmarks/ scripts/ share/: .cpp .hpp .h .py .sh .json .txt .cmake
   and CMakeLists.txt) use none of the phrases of a development log: issue numbers, "the issue", sessions (a
   3D Slicer session is fine), leases, numbered stops, rounds, "this machine" or "the development machine".
   The pages also do not send users to check_docs.py, a test of this repository that users do not run.
   Of a C++ file, its comments, its string literals (what users read in messages) and its test names are read,
   not its code (an API's `GmshSession session;` is no history); of any other file every line. A test name,
   TEST(Suite, Name) or add_test(NAME name), is read as words (`Issue6Cases` and `docs_issue_6` read "Issue 6
   Cases" and "docs issue 6").
2. No test that is gone: every backquoted GoogleTest name `Suite.Name` in docs/*.md names a test that exists
   under tests/ as TEST(Suite, Name), TEST_F or TEST_P, or a parameterised suite's instantiation
   (INSTANTIATE_TEST_SUITE_P(Prefix, Suite, ...) makes `Prefix/Suite.Name/...`).

Each problem is printed as path:line: text. Exit status 1 if there is any, else 0 with a count of what was read.

Usage: no_build_history.py SOURCE_DIR
"""
import pathlib
import re
import sys

# Pages not checked at all, each with its reason; none at present.
EXCLUDED: set = set()

# Files whose hits are known and are being reworded by whoever is changing them now. Their hits are listed as
# pending and do not fail the test; take a file out of this set once it is clean.
PENDING: set = set()

# Scanned for both sets of phrases: the user's pages.
PAGE_DIRS = ["docs"]
PAGE_FILES = ["README.md"]

# Scanned for the build-history phrases only: the source tree.
SOURCE_DIRS = ["core", "apps", "analysis", "io", "monitors", "plugins", "tests", "benchmarks", "scripts", "share"]
SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".py", ".sh", ".json", ".txt", ".cmake"}
SKIPPED_DIRS = ["tests/docs"]  # this check and its neighbours, which must name what they look for

HISTORY = [
    re.compile(r"\bissue \d+", re.IGNORECASE),
    re.compile(r"\bissue's goal", re.IGNORECASE),
    re.compile(r"\bthe issue\b", re.IGNORECASE),
    re.compile(r"(?<!slicer )(?<!slicer's )\bsessions?\b", re.IGNORECASE),
    re.compile(r"\blease\b", re.IGNORECASE),
    re.compile(r"\bstop \d+\b", re.IGNORECASE),
    re.compile(r"\bthis round\b", re.IGNORECASE),
    re.compile(r"\blast round\b", re.IGNORECASE),
    re.compile(r"\bdevelopment machine\b", re.IGNORECASE),
    re.compile(r"\bthis machine\b", re.IGNORECASE),
]
PAGES_ONLY = [
    re.compile(r"check_docs\.py", re.IGNORECASE),  # a test of this repository, not a tool users run
]


def pages(source):
    found = [source / name for name in PAGE_FILES]
    for directory in PAGE_DIRS:
        found += sorted((source / directory).glob("*.md"))
    return [page for page in found if page.is_file()]


def source_files(source):
    skipped = [source / name for name in SKIPPED_DIRS]
    for directory in SOURCE_DIRS:
        for path in sorted((source / directory).rglob("*")):
            if not path.is_file() or any(path.is_relative_to(s) for s in skipped):
                continue
            if path.suffix in SOURCE_SUFFIXES or path.name == "CMakeLists.txt":
                yield path


def lines(path):
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        text = path.read_text(encoding="latin-1")
    return enumerate(text.splitlines(), start=1)


CPP_SUFFIXES = {".cpp", ".hpp", ".h", ".cu", ".cuh"}
GTEST_NAME = re.compile(r"\b(?:TYPED_TEST_P|TYPED_TEST|TEST_F|TEST_P|TEST)\s*\(\s*(\w+)\s*,\s*(\w+)\s*\)")
CMAKE_TEST_NAME = re.compile(r"\badd_test\s*\(\s*NAME\s+([\w.-]+)", re.IGNORECASE)


def as_words(identifier):
    """An identifier read as words: CamelCase, digits and underscores split, so patterns of words can match."""
    words = re.sub(r"(?<=[a-z])(?=[A-Z0-9])|(?<=[A-Z])(?=[A-Z][a-z])|(?<=[0-9])(?=[A-Za-z])", " ", identifier)
    return re.sub(r"[_.-]+", " ", words)


def cpp_readable_text(text):
    """Per line of a C++ file, the text of its comments and string and character literals, code left out."""
    out = [[] for _ in range(text.count("\n") + 1)]
    i, n, line = 0, len(text), 0

    def take(start, end):  # the text[start:end] kept, spread over the lines it spans
        nonlocal line
        for k, piece in enumerate(text[start:end].split("\n")):
            if k:
                line += 1
            out[line].append(piece)

    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
            take(i, end)
            i = end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            take(i, end)
            i = end
        elif c == "R" and i + 1 < n and text[i + 1] == '"' and (i == 0 or not (text[i - 1].isalnum() or
                                                                             text[i - 1] == "_")):
            open_paren = text.find("(", i + 2)
            delimiter = ")" + text[i + 2:open_paren] + '"'
            end = text.find(delimiter, open_paren)
            end = n if end < 0 else end + len(delimiter)
            take(i, end)
            i = end
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):  # 1'000 is a number
            end = i + 1
            while end < n and text[end] != c and text[end] != "\n":
                end += 2 if text[end] == "\\" else 1
            end = min(end + 1, n)
            take(i, end)
            i = end
        else:
            i += 1
    return [" ".join(parts) for parts in out]


def readable_lines(path):
    """(line number, text read, line as written) of a file: for C++ only comments, literals and test names."""
    numbered = list(lines(path))
    if path.suffix in CPP_SUFFIXES:
        text = "\n".join(line for _, line in numbered)
        readable = cpp_readable_text(text)
        for number, line in numbered:
            names = " ".join(as_words(name) for match in GTEST_NAME.finditer(line) for name in match.groups())
            yield number, f"{readable[number - 1]} {names}", line
        return
    for number, line in numbered:
        names = " ".join(as_words(name) for name in CMAKE_TEST_NAME.findall(line))
        yield number, f"{line} {names}", line


def history_hits(source, path, patterns):
    where = path.relative_to(source).as_posix()
    for number, readable, line in readable_lines(path):
        if any(p.search(readable) for p in patterns):
            yield where, f"{where}:{number}: {line.strip()}"


TEST_MACRO = re.compile(r"\b(?:TEST|TEST_F|TEST_P|TYPED_TEST|TYPED_TEST_P)\s*\(\s*(\w+)\s*,\s*(\w+)\s*\)")
INSTANTIATION = re.compile(r"\bINSTANTIATE_(?:TEST_SUITE|TEST_CASE|TYPED_TEST_SUITE)_P\s*\(\s*(\w+)\s*,\s*(\w+)")
# A GoogleTest name in backquotes: Suite.Name, optionally Prefix/Suite.Name/parameter or a pattern with '*'.
DOC_TEST_NAME = re.compile(r"`(?:(\w+)/)?([A-Z]\w*)\.([A-Z]\w*|\*)(?:/[\w*]+)?`")
# Backquoted names of that shape that are not tests: Gmsh's options (its "Mesh" category shares a test suite's name).
NOT_TESTS = {"Mesh.MaxNumThreads1D", "Mesh.MaxNumThreads2D", "Mesh.MaxNumThreads3D", "General.NumThreads"}


def known_tests(source):
    """{(suite, name)} for every test under tests/, and {prefix/suite} for every parameterised instantiation."""
    tests, suites = set(), set()
    for path in (source / "tests").rglob("*"):
        if path.suffix not in CPP_SUFFIXES or not path.is_file():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        tests.update(TEST_MACRO.findall(text))
        suites.update(f"{prefix}/{suite}" for prefix, suite in INSTANTIATION.findall(text))
    return tests, suites


def stale_test_names(source, page, tests, suites):
    where = page.relative_to(source).as_posix()
    suite_names = {suite for suite, _ in tests}
    for number, line in lines(page):
        for match in DOC_TEST_NAME.finditer(line):
            prefix, suite, name = match.groups()
            if f"{suite}.{name}" in NOT_TESTS:
                continue
            # A suite that no test has may still be a test's (its suite renamed or gone) when the name reads like
            # one: a sentence of four words or more, as every test name here is. Shorter ones are taken for
            # something else (a type's member, an option).
            sentence = len(re.findall(r"[A-Z][a-z0-9]", name)) >= 4
            if suite not in suite_names and not (prefix or suite.endswith("Test") or sentence):
                continue
            exists = (suite, name) in tests or (name == "*" and suite in suite_names)
            if prefix and f"{prefix}/{suite}" not in suites:
                exists = False
            if not exists:
                yield where, f"{where}:{number}: `{match.group(0)[1:-1]}` is not a test under tests/"


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    source = pathlib.Path(sys.argv[1]).resolve()
    this = pathlib.Path(__file__).resolve()
    problems, pending, scanned = [], [], 0

    def record(hits):
        for where, text in hits:
            (pending if where in PENDING else problems).append(text)

    checked_pages = [p for p in pages(source) if p.relative_to(source).as_posix() not in EXCLUDED]
    for page in checked_pages:
        scanned += 1
        record(history_hits(source, page, HISTORY + PAGES_ONLY))
    for path in source_files(source):
        if path.resolve() == this or path.relative_to(source).as_posix() in EXCLUDED:
            continue
        scanned += 1
        record(history_hits(source, path, HISTORY))

    tests, suites = known_tests(source)
    for page in checked_pages:
        if page.parent.name == "docs":
            record(stale_test_names(source, page, tests, suites))

    if pending:
        print(f"{len(pending)} known hit(s) in files being reworded (PENDING), not counted:")
        for text in pending:
            print("  " + text)
    if problems:
        print("The documentation and the source speak of how the project was built, or name tests that are gone:")
        for text in problems:
            print(text)
        return 1
    print(f"{scanned} files read, {len(checked_pages)} pages' test names checked against {len(tests)} tests: "
          "nothing about how the project was built, no test that is gone")
    return 0


if __name__ == "__main__":
    sys.exit(main())
