#!/usr/bin/python3
"""Figures that cannot drift: docs quote a shipped scene's nodes, steps and result as docs/scenes.md's table gives
them (benchmarks/scene_table.py measures it). In every sentence of README.md and docs/*.md that names a shipped scene
(its file, or "the default scene", "the analytic scene", "the label-map scene"), a count of steps or nodes, or a
force in newtons, that lies within a factor of two of the table's figure for that scene must be the table's figure
(a force to the digits quoted; "about" a figure, within 5%): a near miss is a stale copy. A sentence about another
run of the scene says so with an override (`--set`) or the marker `<!-- other run -->` (invisible in the page).

  scene_figures.py SOURCE_DIR
"""
import re
import sys
from pathlib import Path

ALIASES = {"the default scene": "needle_small_sample.json", "the default needle scene": "needle_small_sample.json", "the analytic scene": "needle_brain_phantom.json",
           "the label-map scene": "needle_brain_label_map.json"}
OTHER_RUN = ("--set", "<!-- other run -->")


def number(text):
    return float(text.replace(",", ""))


def read_table(scenes_md):
    """{scene: {"nodes": n, "steps": n, "force": N}} from the rows between the scene-table markers."""
    page = scenes_md.read_text()
    block = page[page.index("<!-- scene-table:begin -->"):page.index("<!-- scene-table:end -->")]
    table = {}
    for line in block.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 7 or not cells[0].startswith("`"):
            continue
        force = re.match(r"([\d.e+-]+) N", cells[5])
        table[cells[0].strip("`")] = {"nodes": number(cells[2]), "steps": number(cells[4]),
                                      "force": float(force.group(1)) if force else None}
    if len(table) < 8:
        sys.exit(f"{scenes_md}: the scene table has {len(table)} rows; regenerate it with benchmarks/scene_table.py")
    return table


def sentences(text):
    """Paragraphs cut into sentences; a table row is a sentence of its own."""
    for paragraph in re.split(r"\n\s*\n", text):
        for part in re.split(r"(?<=[.;:])\s+(?=[A-Z(*`])|\n(?=\|)", paragraph):
            yield part.replace("\n", " ")


def drifted(sentence, table):
    """The quotes in `sentence` that nearly match a named scene's figure without being it."""
    named = {scene for scene in table if scene in sentence}
    named |= {scene for alias, scene in ALIASES.items() if alias in sentence.lower()}
    if not named or any(marker in sentence for marker in OTHER_RUN):
        return []
    pattern = r"(about |around )?(\d[\d,]*) (steps|nodes)\b|(about |around )?(\d+\.\d+) (N)\b"
    out = []
    for m in re.finditer(pattern, sentence):
        about = bool(m.group(1) or m.group(4))
        kind = m.group(3) or "force"
        value = number(m.group(2) or m.group(5))
        figures = [table[scene][kind] for scene in named if table[scene][kind]]
        if not figures:
            continue
        # A force to the digits it is quoted with; "about" a figure within 5%.
        digits = len((m.group(5) or "0.").split(".")[1])
        allowed = [0.05 * f if about else (0.5 * 10 ** -digits if kind == "force" else 0) for f in figures]
        same = any(abs(value - f) <= a for f, a in zip(figures, allowed))
        near = any(0.5 <= value / f <= 2 for f in figures)
        if near and not same:
            out.append(f"{m.group(0)} (the table: {', '.join(f'{f:g}' for f in figures)})")
    return out


def main():
    source = Path(sys.argv[1])
    table = read_table(source / "docs/scenes.md")
    failures = []
    for page in [source / "README.md"] + sorted((source / "docs").glob("*.md")):
        for sentence in sentences(page.read_text()):
            for quote in drifted(sentence, table):
                failures.append(f"{page.relative_to(source)}: {quote}: \"{sentence[:160]}\"")
    print(f"{len(table)} scenes' figures checked in {1 + len(list((source / 'docs').glob('*.md')))} pages")
    if failures:
        sys.exit("quotes of a shipped scene's figures that are not the table's (docs/scenes.md):\n" +
                 "\n".join(failures))


if __name__ == "__main__":
    main()
