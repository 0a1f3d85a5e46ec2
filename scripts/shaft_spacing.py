#!/usr/bin/python3
"""The spacing beside a needle's shaft: the mean edge length of the tets whose centroid lies within a radius of the
needle's path (entry to entry + depth x direction), from a mesh written by `mtled mesh` (Abaqus .inp). What the
kinematic needle holds is a sleeve about as thick as this spacing, and its force follows it (docs/stability.md).

    build/bin/mtled mesh share/scenes/needle_brain_phantom.json -o runs/brain.inp
    scripts/shaft_spacing.py runs/brain.inp --entry 0.025 0.006 0.07 --direction 0 0 -1 --depth 0.1

Debian's python3 with numpy.
"""
import argparse

import numpy as np

from abaqus_inp import read_inp as read_abaqus


def read_inp(path):
    """Node coordinates and the C3D4 tets (rows into them) of a mesh `mtled mesh` wrote."""
    nodes, tets, _ = read_abaqus(path, "C3D4")
    ids = sorted(nodes)
    position = {node: row for row, node in enumerate(ids)}
    return np.array([nodes[i] for i in ids]), np.array([[position[n] for n in tet] for tet in tets])


def shaft_spacing(points, tets, entry, direction, depth, radius):
    """(mean edge length, tets counted) of the tets whose centroid is within `radius` of the path."""
    direction = direction / np.linalg.norm(direction)
    centroids = points[tets].mean(axis=1)
    along = np.clip((centroids - entry) @ direction, 0.0, depth)
    near = np.linalg.norm(centroids - (entry + along[:, None] * direction), axis=1) < radius
    corners = points[tets[near]]
    edges = [np.linalg.norm(corners[:, a] - corners[:, b], axis=1) for a in range(4) for b in range(a + 1, 4)]
    return float(np.mean(edges)), int(near.sum())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", help="an Abaqus .inp file written by `mtled mesh`")
    parser.add_argument("--entry", type=float, nargs=3, required=True, help="the needle's entry point (m)")
    parser.add_argument("--direction", type=float, nargs=3, required=True)
    parser.add_argument("--depth", type=float, required=True, help="the needle's final depth (m)")
    parser.add_argument("--radius", type=float, default=0.005, help="distance from the path counted (m)")
    args = parser.parse_args()
    points, tets = read_inp(args.mesh)
    spacing, count = shaft_spacing(points, tets, np.array(args.entry), np.array(args.direction), args.depth,
                                   args.radius)
    print(f"{1e3 * spacing:.3f} mm mean edge over {count} tets within {1e3 * args.radius:g} mm of the path")


if __name__ == "__main__":
    main()
