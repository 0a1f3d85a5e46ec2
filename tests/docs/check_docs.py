#!/usr/bin/env python3
"""The documentation stays true to the code: every relative link in README.md and docs/*.md points at a file
that exists, and every `mtled run`/`mtled validate` example (with its --set overrides) names a scene the
built mtled accepts, and every `mtled study` or `mtled fit` example names a study or fit file that exists; a size
quoted with the command that counts it ("N lines (`find core -name '*.[ch]pp' | xargs cat | wc -l`)") is within 2%
of that count.

Usage: check_docs.py SOURCE_DIR MTLED_EXECUTABLE
"""
import pathlib
import re
import shlex
import subprocess
import sys

source = pathlib.Path(sys.argv[1])
mtled = sys.argv[2]
pages = [source / "README.md"] + sorted((source / "docs").glob("*.md"))
problems = []
checked_links = checked_commands = 0

for page in pages:
    text = page.read_text()
    for line_number, line in enumerate(text.splitlines(), 1):
        where = f"{page.relative_to(source)}:{line_number}"
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", line):
            if re.match(r"[a-z]+://", target) or target.startswith("mailto:"):
                continue
            checked_links += 1
            if not (page.parent / target).exists():
                problems.append(f"{where}: link to {target}, which does not exist")
        # Commands shown as examples: an indented line or a table cell starting with build/bin/mtled; a quote
        # ends one (a command quoted inside another, as farm-bench's --vs takes it).
        match = re.search(r"build/bin/mtled (run|validate|study|fit) ([^|`#\"']*)", line)
        if not match:
            continue
        words = shlex.split(match.group(2))
        if not words:
            continue
        checked_commands += 1
        target = source / words[0]
        if match.group(1) == "study":
            if not target.exists():
                problems.append(f"{where}: the study {words[0]} does not exist")
            continue
        if match.group(1) == "fit":  # shipped fit files exist (fit_test checks that they read); a user's own may not
            if words[0].startswith("share/") and not target.exists():
                problems.append(f"{where}: the fit file {words[0]} does not exist")
            continue
        if not target.exists():
            if words[0].startswith("share/"):
                problems.append(f"{where}: the scene {words[0]} does not exist")
            continue  # a user's own scene (my_scene.json)
        overrides = []
        for i, word in enumerate(words):
            if word == "--set" and i + 1 < len(words):
                overrides += ["--set", words[i + 1]]
        result = subprocess.run([mtled, "validate", str(target)] + overrides, capture_output=True, text=True)
        if result.returncode != 0:
            problems.append(f"{where}: `mtled validate {words[0]} {' '.join(overrides)}` failed:\n{result.stdout}{result.stderr}")


def kernel_lines():
    return sum(len(path.read_text().splitlines()) for folder in ["core"] for path in (source / folder).rglob("*.[ch]pp"))


for page in pages:
    for line_number, line in enumerate(page.read_text().splitlines(), 1):
        for quoted in re.findall(r"([\d,]+) lines \(`find core -name '\*\.\[ch\]pp' \| xargs cat \| wc -l`\)", line):
            actual = kernel_lines()
            if abs(int(quoted.replace(",", "")) - actual) > 0.02 * actual:
                problems.append(f"{page.relative_to(source)}:{line_number}: the kernel is quoted at {quoted} lines; "
                                f"the command counts {actual:,}")

print(f"checked {checked_links} links and {checked_commands} example commands in {len(pages)} pages")
for problem in problems:
    print(problem)
sys.exit(1 if problems else 0)
