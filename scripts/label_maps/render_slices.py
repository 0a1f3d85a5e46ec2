#!/usr/bin/python3
"""Draws one slice through images side by side, as PNG: a label map before and after `mtled warp`, say.

  render_slices.py OUT.png IMAGE [IMAGE ...] [--axis x|y|z] [--at MM] [--line MARKUPS.mrk.json] [--scale N]

Each IMAGE (NRRD as mtled and 3D Slicer write it: attached header, raw or gzip) is cut by the plane of constant
physical coordinate --axis = --at millimetres, in the image's own frame, through its nearest voxel layer; the
in-plane axes are the other two index axes, the second drawn upwards. Whole-number images are drawn with one colour
per label (0 black); others in grey from their minimum to their maximum. With --line, a Slicer markups line (its
first two control points) is drawn on every panel in its projection on the plane, in the frame the markups file
names (turned to the image's). A last panel marks in red the voxels where the last image differs from the first.
Needs numpy and PIL (Debian python3-numpy, python3-pil).
"""
import argparse
import gzip
import json
import re
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

COLOURS = [(0, 0, 0), (230, 159, 0), (86, 180, 233), (0, 158, 115), (240, 228, 66), (0, 114, 178), (213, 94, 0),
           (204, 121, 167)]
TYPES = {"unsigned char": np.uint8, "uchar": np.uint8, "signed char": np.int8, "short": np.int16,
         "unsigned short": np.uint16, "int": np.int32, "unsigned int": np.uint32, "float": np.float32,
         "double": np.float64}


def read_nrrd(path):
    """(header fields, "key:=value" pairs, values indexed [k, j, i] or, for vectors, [k, j, i, component])."""
    raw = Path(path).read_bytes()
    end = raw.index(b"\n\n")
    fields, pairs = {}, {}
    for line in raw[:end].decode().splitlines()[1:]:
        if line.startswith("#"):
            continue
        if ":=" in line:
            key, value = line.split(":=", 1)
            pairs[key] = value
        else:
            key, value = line.split(": ", 1)
            fields[key.lower()] = value
    data = raw[end + 2:]
    if fields["encoding"] in ("gzip", "gz"):
        data = gzip.decompress(data)
    sizes = [int(s) for s in fields["sizes"].split()]
    return fields, pairs, np.frombuffer(data, dtype=TYPES[fields["type"]]).reshape(list(reversed(sizes)))


def placement(fields):
    """(frame, origin mm, axes mm as columns) of a NRRD header's fields."""
    vectors = [[float(x) for x in v.split(",")] for v in re.findall(r"\(([^)]*)\)", fields["space directions"])]
    origin = np.array([float(x) for x in re.findall(r"\(([^)]*)\)", fields["space origin"])[0].split(",")])
    space = "RAS" if fields.get("space", "").startswith("right") else "LPS"
    return space, origin, np.array(vectors).T


def read_scalar_image(path):
    """(frame, origin mm, axes mm as columns, values indexed [k, j, i])."""
    fields, _, values = read_nrrd(path)
    if fields.get("dimension") != "3":
        sys.exit(f"{path}: dimension {fields.get('dimension')}: draw a scalar image (3 axes)")
    return (*placement(fields), values)


def cut(image, axis, at):
    """The slice's pixels (rows from the top) and a function taking a point (mm) to pixel coordinates."""
    space, origin, axes, values = image
    along = "xyz".index(axis)
    # The index axis that runs most along the physical axis, and the layer whose centre is nearest --at.
    index_axis = int(np.argmax(np.abs(axes[along, :])))
    layer = int(round((at - origin[along]) / axes[along, index_axis]))
    layer = min(max(layer, 0), values.shape[2 - index_axis] - 1)
    plane = np.take(values, layer, axis=2 - index_axis)  # the remaining axes, slowest first
    across, up = [a for a in range(3) if a != index_axis]
    pixels = plane[::-1, :]  # rows: `up` from the top down; columns: `across`
    to_index = np.linalg.inv(axes)

    def to_pixel(point):
        q = to_index @ (np.asarray(point) - origin)
        return q[across], pixels.shape[0] - 1 - q[up]

    return pixels, to_pixel


def draw(pixels, whole):
    if whole:
        rgb = np.array(COLOURS, dtype=np.uint8)[pixels.astype(np.int64) % len(COLOURS)]
    else:
        lo, hi = float(pixels.min()), float(pixels.max())
        grey = np.uint8(np.clip(255 * (pixels - lo) / max(hi - lo, 1e-30), 0, 255))
        rgb = np.stack([grey] * 3, axis=-1)
    return Image.fromarray(rgb, "RGB")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("images", nargs="+")
    parser.add_argument("--axis", default="x", choices=["x", "y", "z"])
    parser.add_argument("--at", type=float, default=0.0, help="the plane's coordinate (mm)")
    parser.add_argument("--line", help="a Slicer markups line to draw")
    parser.add_argument("--scale", type=int, default=2, help="pixels per voxel")
    args = parser.parse_args()
    images = [read_scalar_image(path) for path in args.images]
    panels = []
    for image in images:
        pixels, to_pixel = cut(image, args.axis, args.at)
        panel = draw(pixels, np.issubdtype(pixels.dtype, np.integer))
        panel = panel.resize((panel.width * args.scale, panel.height * args.scale), Image.NEAREST)
        if args.line:
            markups = json.loads(Path(args.line).read_text())["markups"][0]
            flip = np.array([-1.0, -1.0, 1.0]) if markups.get("coordinateSystem", "LPS") != image[0] else np.ones(3)
            ends = [flip * np.array(p["position"], float) for p in markups["controlPoints"][:2]]
            (a, b), (c, d) = (to_pixel(p) for p in ends)
            s = args.scale
            ImageDraw.Draw(panel).line([(s * a + s / 2, s * b + s / 2), (s * c + s / 2, s * d + s / 2)],
                                       fill=(255, 255, 255), width=1)
        panels.append((panel, pixels))
    if len(images) > 1:
        first, last = panels[0][1], panels[-1][1]
        if first.shape == last.shape:
            changed = np.where((first != last)[..., None], np.array([220, 30, 30], np.uint8),
                               np.uint8(0.4 * np.asarray(draw(first, np.issubdtype(first.dtype, np.integer)))))
            panel = Image.fromarray(changed.astype(np.uint8), "RGB")
            panels.append((panel.resize((panel.width * args.scale, panel.height * args.scale), Image.NEAREST), None))
    gap = 4
    width = sum(p.width for p, _ in panels) + gap * (len(panels) - 1)
    sheet = Image.new("RGB", (width, max(p.height for p, _ in panels)), (255, 255, 255))
    x = 0
    for panel, _ in panels:
        sheet.paste(panel, (x, 0))
        x += panel.width + gap
    sheet.save(args.out)
    print(f"{args.out}: {len(panels)} panels, {sheet.width} x {sheet.height} pixels")


if __name__ == "__main__":
    main()
