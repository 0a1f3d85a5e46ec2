#!/usr/bin/python3
"""Writes label maps of simple shapes, as 3D Slicer and nibabel save them, for the label_map mesh source's tests,
the shipped brain-phantom scene and the documentation.

  write_label_map.py SHAPE OUT [--size N] [--spacing MM] [--origin X Y Z] [--directions 9 numbers]
                     [--space LPS|RAS] [--encoding raw|gzip] [--type uint8|int16|int32|float32]

SHAPE: "sphere" (label 1, radius 0.35 of the box), "two_spheres" (labels 1 and 2 side by side), "cube" (label 1,
the middle half of each axis), "brain" (the brain phantom's four ellipsoids: hemispheres 1, cerebellum 2, stem 3),
"marker" (label 1 in voxel (1, 2, 3) only). OUT's name picks the format: .nrrd / .seg.nrrd (written by hand, as
Slicer writes them: gzip, "space directions", segment names in .seg.nrrd) or .nii / .nii.gz (nibabel; the sform and
qform from the same affine). Needs numpy (and nibabel for NIfTI).
"""
import argparse
import gzip
import sys

import numpy as np


def shape_labels(shape, n, spacing):
    """Labels on an n^3 grid of voxel centres, index order (i, j, k)."""
    i, j, k = np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")
    centre = (n - 1) / 2.0
    x, y, z = (i - centre) / n, (j - centre) / n, (k - centre) / n  # -0.5 .. 0.5 of the box
    labels = np.zeros((n, n, n), dtype=np.int32)
    if shape == "sphere":
        labels[x * x + y * y + z * z <= 0.35 ** 2] = 1
    elif shape == "two_spheres":
        labels[(x + 0.2) ** 2 + y * y + z * z <= 0.18 ** 2] = 1
        labels[(x - 0.2) ** 2 + y * y + z * z <= 0.18 ** 2] = 2
    elif shape == "cube":
        labels[(abs(x) < 0.25) & (abs(y) < 0.25) & (abs(z) < 0.25)] = 1
    elif shape == "marker":
        labels[1, 2, 3] = 1
    elif shape == "brain":
        # The brain_phantom generator's design (metres, box 0.14 x 0.156 x 0.14 about the origin), on a cube grid
        # of side 0.16 m: ellipsoid (centre, semi-axes, label).
        side = 0.16
        X, Y, Z = x * side, y * side, z * side
        design = [((0.025, 0.006, 0.015), (0.045, 0.072, 0.055), 1), ((-0.025, 0.006, 0.015), (0.045, 0.072, 0.055), 1),
                  ((0.0, -0.045, -0.030), (0.050, 0.033, 0.025), 2), ((0.0, -0.012, -0.030), (0.014, 0.016, 0.040), 3)]
        for c, a, label in reversed(design):
            inside = ((X - c[0]) / a[0]) ** 2 + ((Y - c[1]) / a[1]) ** 2 + ((Z - c[2]) / a[2]) ** 2 <= 1.0
            labels[inside & (labels == 0)] = label
    else:
        sys.exit(f"unknown shape {shape}")
    return labels


def write_nrrd(path, labels, axes_mm, origin_mm, space, encoding, dtype, segments):
    nrrd_type = {"uint8": "unsigned char", "int16": "short", "int32": "int", "float32": "float"}[dtype]
    lines = ["NRRD0004", "# Complete NRRD file format specification at:",
             "# http://teem.sourceforge.net/nrrd/format.html", f"type: {nrrd_type}", "dimension: 3",
             f"space: {space}", "sizes: " + " ".join(str(s) for s in labels.shape),
             "space directions: " + " ".join("(%.17g,%.17g,%.17g)" % tuple(axes_mm[:, a]) for a in range(3)),
             "kinds: domain domain domain", "endian: little", f"encoding: {encoding}",
             "space origin: (%.17g,%.17g,%.17g)" % tuple(origin_mm)]
    for n, (label, name) in enumerate(segments):
        lines += [f"Segment{n}_Name:={name}", f"Segment{n}_LabelValue:={label}", f"Segment{n}_Layer:=0"]
    data = labels.astype(dtype).tobytes(order="F")  # i fastest
    if encoding == "gzip":
        data = gzip.compress(data, mtime=0)  # the same bytes on every run
    with open(path, "wb") as f:
        f.write(("\n".join(lines) + "\n\n").encode())
        f.write(data)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("shape")
    p.add_argument("out")
    p.add_argument("--size", type=int, default=48)
    p.add_argument("--spacing", type=float, default=None, help="mm (default: 16 mm box, or 160 mm for brain)")
    p.add_argument("--origin", type=float, nargs=3, default=None, help="mm, centre of voxel (0,0,0)")
    p.add_argument("--directions", type=float, nargs=9, default=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                   help="unit axis directions, one after another")
    p.add_argument("--space", default="left-posterior-superior")
    p.add_argument("--encoding", default="gzip")
    p.add_argument("--type", default="uint8")
    a = p.parse_args()
    box = 160.0 if a.shape == "brain" else 16.0
    spacing = a.spacing if a.spacing else box / a.size
    labels = shape_labels(a.shape, a.size, spacing)
    axes = np.array(a.directions, dtype=float).reshape(3, 3).T * spacing  # columns: steps along i, j, k (mm)
    origin = np.array(a.origin if a.origin else [-(a.size - 1) / 2.0 * spacing] * 3)
    names = {"brain": [(1, "cerebrum"), (2, "cerebellum"), (3, "brain_stem")],
             "two_spheres": [(1, "left"), (2, "right")]}.get(a.shape, [(1, "tissue")])
    if a.out.endswith(".nrrd"):
        write_nrrd(a.out, labels, axes, origin, a.space, a.encoding, a.type, names if a.out.endswith(".seg.nrrd") else [])
    else:
        import nibabel
        affine = np.eye(4)
        affine[:3, :3], affine[:3, 3] = axes, origin
        image = nibabel.Nifti1Image(labels.astype(a.type), affine)
        image.header.set_xyzt_units("mm")
        nibabel.save(image, a.out)


if __name__ == "__main__":
    main()
