#!/usr/bin/python3
"""Draws a run's displacement magnitude on a plane cut through its body, as PNG with a colour bar: the picture the
MTLED papers show of a needle insertion (the field on a cut through the needle's plane).

  render_result.py RUN OUT.png [--axis x|y|z] [--at MM] [--deformed] [--pixel MM] [--max MM] [--title TEXT]

RUN is a run folder (its result.vtu) or a result .vtu. The plane is the one of constant coordinate --axis = --at
millimetres (default: through the middle of the body), in the result's coordinates; the in-plane axes are the other
two in order, the second drawn upwards. The field is the run's interpolated displacement, read where the plane cuts
each background tet (linear in the tet, as ParaView's slice shows it), in the reference configuration or, with
--deformed, where the tissue is after the run. Colours run from dark blue (zero) to yellow (--max, default the
largest value on the cut); the background outside the body is white.
Needs numpy, PIL and VTK (Debian python3-numpy, python3-pil, and python3-paraview, whose `vtk` module it uses).
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import vtk
from PIL import Image, ImageDraw
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

# Stops of the viridis colour map (perceptually uniform, readable in grey and by the colour-blind).
STOPS = np.array([(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)], dtype=float)


def colour_table(levels=256):
    t = np.linspace(0.0, 1.0, levels) * (len(STOPS) - 1)
    low = np.minimum(t.astype(int), len(STOPS) - 2)
    f = (t - low)[:, None]
    return np.rint((1 - f) * STOPS[low] + f * STOPS[low + 1]).astype(np.uint8)


def read_result(path):
    """(the grid, millimetres per unit of its coordinates)."""
    path = Path(path)
    if path.is_dir():
        path = path / "result.vtu"
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    if grid.GetNumberOfPoints() == 0 or grid.GetPointData().GetArray("displacement") is None:
        sys.exit(f"{path}: not an mtled result (no points, or no point array \"displacement\")")
    unit = grid.GetFieldData().GetAbstractArray("LENGTH_UNIT")
    return grid, 1.0 if unit is not None and unit.GetValue(0) == "mm" else 1e3


def cut(grid, mm_per_unit, axis, at_mm, pixel_mm, deformed):
    """(magnitude in mm on the plane's pixels, NaN outside; the in-plane axes; the plane's lower corner in mm)."""
    points = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
    displacement = vtk_to_numpy(grid.GetPointData().GetArray("displacement")).astype(float)
    if deformed:
        moved = vtk.vtkPoints()
        moved.SetData(numpy_to_vtk(points + displacement, deep=True))
        copy = vtk.vtkUnstructuredGrid()
        copy.DeepCopy(grid)
        copy.SetPoints(moved)
        grid, points = copy, points + displacement
    a = "xyz".index(axis)
    u, v = [c for c in range(3) if c != a]
    lower, upper = points.min(axis=0) * mm_per_unit, points.max(axis=0) * mm_per_unit
    at = 0.5 * (lower[a] + upper[a]) if at_mm is None else at_mm
    if not lower[a] <= at <= upper[a]:
        sys.exit(f"--at {at} mm: the body spans {lower[a]:.3g} to {upper[a]:.3g} mm along {axis}")
    # Pixel centres from the lower bound on, every pixel_mm, up to the upper bound (rounding aside).
    n_u = int(np.floor((upper[u] - lower[u]) / pixel_mm + 1e-6)) + 1
    n_v = int(np.floor((upper[v] - lower[v]) / pixel_mm + 1e-6)) + 1
    plane = np.zeros((n_v * n_u, 3))
    jj, ii = np.mgrid[0:n_v, 0:n_u]
    plane[:, a] = at
    plane[:, u] = lower[u] + pixel_mm * ii.ravel()
    plane[:, v] = lower[v] + pixel_mm * jj.ravel()
    probe_points = vtk.vtkPoints()
    probe_points.SetData(numpy_to_vtk(plane / mm_per_unit, deep=True))
    probes = vtk.vtkPolyData()
    probes.SetPoints(probe_points)
    probe = vtk.vtkProbeFilter()
    probe.SetInputData(probes)
    probe.SetSourceData(grid)
    probe.Update()
    out = probe.GetOutput()
    valid = vtk_to_numpy(out.GetPointData().GetArray(probe.GetValidPointMaskArrayName())).astype(bool)
    values = vtk_to_numpy(out.GetPointData().GetArray("displacement")).astype(float)
    magnitude = np.where(valid, np.linalg.norm(values, axis=1) * mm_per_unit, np.nan)
    return magnitude.reshape(n_v, n_u), (u, v), (lower[u], lower[v]), at


def draw(magnitude, top, axes, corner, at, axis, title, scale):
    table = colour_table()
    level = np.clip(np.rint(np.nan_to_num(magnitude / top) * 255), 0, 255).astype(int)
    rgb = table[level]
    rgb[np.isnan(magnitude)] = 255
    field = Image.fromarray(rgb[::-1].astype(np.uint8))  # the second in-plane axis upwards
    field = field.resize((field.width * scale, field.height * scale), Image.NEAREST)
    bar_width, margin, text_height = 16, 10, 14
    names = "xyz"
    title = title or f"|u| on {axis} = {at:.3g} mm"
    caption = f"{names[axes[0]]} from {corner[0]:.3g} mm (right), {names[axes[1]]} from {corner[1]:.3g} mm (up)"
    text_width = int(max(ImageDraw.Draw(Image.new("RGB", (1, 1))).textlength(t) for t in (title, caption)))
    width = max(field.width + 3 * margin + bar_width + 70, text_width + 2 * margin)
    sheet = Image.new("RGB", (width, field.height + 2 * margin + 2 * text_height), (255, 255, 255))
    sheet.paste(field, (margin, margin + text_height))
    bar = np.repeat(table[::-1][:, None, :], bar_width, axis=1)
    bar = Image.fromarray(bar).resize((bar_width, field.height), Image.NEAREST)
    x_bar = field.width + 2 * margin
    sheet.paste(bar, (x_bar, margin + text_height))
    pen = ImageDraw.Draw(sheet)
    pen.text((x_bar + bar_width + 4, margin + text_height - 6), f"{top:.3g} mm", fill=(0, 0, 0))
    pen.text((x_bar + bar_width + 4, margin + text_height + field.height - 8), "0", fill=(0, 0, 0))
    pen.text((margin, 2), title, fill=(0, 0, 0))
    pen.text((margin, margin + text_height + field.height + 2), caption, fill=(0, 0, 0))
    return sheet


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run")
    parser.add_argument("out")
    parser.add_argument("--axis", choices=list("xyz"), default="y")
    parser.add_argument("--at", type=float, help="mm (default: the middle of the body)")
    parser.add_argument("--deformed", action="store_true")
    parser.add_argument("--pixel", type=float, help="mm per pixel (default: 1/300 of the cut's larger side)")
    parser.add_argument("--max", type=float, help="mm at the top of the colour bar (default: the largest on the cut)")
    parser.add_argument("--scale", type=int, default=1, help="screen pixels per pixel")
    parser.add_argument("--title")
    args = parser.parse_args()
    grid, mm_per_unit = read_result(args.run)
    bounds = np.array(grid.GetBounds()).reshape(3, 2) * mm_per_unit
    pixel = args.pixel or (bounds[:, 1] - bounds[:, 0]).max() / 300.0
    magnitude, axes, corner, at = cut(grid, mm_per_unit, args.axis, args.at, pixel, args.deformed)
    if np.isnan(magnitude).all():
        sys.exit(f"the plane {args.axis} = {at} mm does not cut the body")
    top = args.max or float(np.nanmax(magnitude)) or 1.0
    draw(magnitude, top, axes, corner, at, args.axis, args.title, args.scale).save(args.out)
    print(f"{args.out}: |u| from {np.nanmin(magnitude):.4g} to {np.nanmax(magnitude):.4g} mm on {args.axis} = "
          f"{at:.4g} mm, {magnitude.shape[1]} x {magnitude.shape[0]} pixels of {pixel:.3g} mm")


if __name__ == "__main__":
    main()
