#!/usr/bin/env python3
"""The figures mtled writes, drawn by a real SVG renderer (librsvg's rsvg-convert), laid out correctly.

For every SVG in a folder (written by svg_samples through the functions `mtled study` and `mtled compare`
use): each text, each legend symbol and each data point is drawn alone, and where its ink lands is measured.
Every text must lie inside the figure (not clipped at an edge), and no text may touch another text, a legend
symbol or a data point.

Usage: figures_render.py SVG_SAMPLES_EXECUTABLE FOLDER
"""
import copy
import io
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

from PIL import Image, ImageChops

NS = "{http://www.w3.org/2000/svg}"
DRAWN = {NS + t for t in ("text", "circle", "line", "path", "rect")}


def render(root):
    png = subprocess.run(["rsvg-convert", "-f", "png"], input=ET.tostring(root), capture_output=True, check=True).stdout
    image = Image.open(io.BytesIO(png)).convert("RGB")
    return image.size, ImageChops.difference(image, Image.new("RGB", image.size, "white")).getbbox()


def items(root):
    """(kind, description, element) for the texts, legend symbols and data points."""
    found = []
    for parent in root.iter():
        for e in parent:
            if e.tag == NS + "text":
                found.append(("text", (e.text or "").strip(), e))
            elif e.tag in (NS + "circle", NS + "line") and (parent.get("id") in ("legend", "points")):
                found.append(("symbol", e.tag[len(NS):] + " in " + parent.get("id"), e))
    return found


def ink_boxes(path):
    tree = ET.parse(path)
    root = tree.getroot()
    listed = items(root)
    drawn = [e for e in root.iter() if e.tag in DRAWN]
    background = drawn[0]  # the white rectangle
    index = {id(e): i for i, e in enumerate(root.iter())}
    elements = list(root.iter())
    boxes = []
    for kind, what, element in listed:
        alone = copy.deepcopy(root)
        copies = list(alone.iter())
        keep = {index[id(element)], index[id(background)]}
        for i, e in enumerate(elements):
            if e.tag in DRAWN and i not in keep:
                copies[i].set("visibility", "hidden")
        size, box = render(alone)
        if box is not None:
            boxes.append((kind, what, box))
    return size, boxes


def overlap(a, b):
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def main():
    samples, folder = sys.argv[1], sys.argv[2]
    subprocess.run([samples, folder], check=True)
    problems = []
    files = sorted(f for f in os.listdir(folder) if f.endswith(".svg"))
    assert files, "no figures written"
    for file in files:
        (width, height), boxes = ink_boxes(os.path.join(folder, file))
        texts = [b for b in boxes if b[0] == "text"]
        for _, what, box in texts:
            if box[0] < 1 or box[1] < 1 or box[2] > width - 1 or box[3] > height - 1:
                problems.append(f"{file}: text {what!r} at {box} is clipped by the figure's edge ({width} x {height})")
        for i, (kind_a, what_a, box_a) in enumerate(boxes):
            for kind_b, what_b, box_b in boxes[i + 1:]:
                if "text" in (kind_a, kind_b) and overlap(box_a, box_b):
                    problems.append(f"{file}: {kind_a} {what_a!r} {box_a} overlaps {kind_b} {what_b!r} {box_b}")
        print(f"{file}: {len(texts)} texts, {len(boxes) - len(texts)} symbols and points checked")
    for p in problems:
        print("FAIL:", p)
    if problems:
        sys.exit(f"{len(problems)} layout problems")
    print("all figures laid out correctly")


if __name__ == "__main__":
    main()
