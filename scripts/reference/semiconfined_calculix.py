#!/usr/bin/env python3
"""An independent finite-element reference for the semi-confined compression (share/scenes/
compression_semiconfined.json): CalculiX (Debian's calculix-ccx) with quadratic elements meshed by Gmsh, geometric
nonlinearity, the same Ogden law and parameters. Both faces are bonded to the platens (bottom fixed, top moved
down with its radial displacement held), the side free. CalculiX's Ogden law with N = 1 is mtled's: W = (2 mu /
alpha^2)(sum_i lambdabar_i^alpha - 3) + (1/D)(J - 1)^2 (lambdabar: the isochoric stretches). The top platen's total
reaction is printed at 5, 10, 15 and 20% compression, on each refinement, into a CSV. First it checks the setup on
the homogeneous uniaxial case (one element, frictionless ends) against the closed form.

Two discretisations:
- 3D (default): the cylinder (30 mm across, 17 mm high) as a quadrilateral mesh of the disc extruded in layers,
  20-node hexahedra with reduced integration (C3D20R), uniform element size SIZE_MM (default 3 2 1.5).
- --axisymmetric: the half cross-section (r, z) as 8-node axisymmetric quadrilaterals with full integration
  (CAX8), graded toward the two bonded rims (r = R at z = 0 and z = H), where the stress is singular: the
  element size is GROWTH times the distance to the nearer rim, at least SIZE_MM (the corner size, default
  0.4 0.2 0.1 0.05) and at most 1 mm. Refining only the corner is what converges here: the uniform 3D meshes
  converge as h^0.45. (Reduced integration, CAX8R, fails to converge in Newton's method once the corner elements
  are below about 0.25 mm: hourglassing in the crushed corner.)

With --surface (axisymmetric only) it also prints, at each compression, the free side's profile under the top rim:
its smallest meridional stretch (a free surface of a neo-Hookean solid compressed below a stretch of about 0.65
creases: Hong, Zhao and Suo, Appl. Phys. Lett. 95, 111901, 2009) and how far it rose above the top platen's plane
(the side rolling onto the platen, which this model, without contact, lets it pass through).

Usage: semiconfined_calculix.py OUTPUT.csv [SIZE_MM ...] [--axisymmetric] [--surface] [--check]   (needs gmsh and
ccx; --check asserts that the force grows with compression, ever faster)
"""
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))  # scripts/
from abaqus_inp import read_inp  # noqa: E402

MU, ALPHA, D = 722.0, -1.3, 5.57738e-5  # the scene's Ogden parameters (Pa, 1, 1/Pa)
RADIUS, HEIGHT, STROKE = 0.015, 0.017, 0.0034  # m: 20% nominal compression
FRACTIONS = (0.25, 0.5, 0.75, 1.0)  # of the stroke: 5, 10, 15, 20%
# The axisymmetric meshes: element size GROWTH x the distance to the nearer bonded rim, between the corner size
# and BULK_SIZE. Halving BULK_SIZE and GROWTH (0.5 mm, 0.125) moves the forces at 5 to 15% by at most 1e-5 N
# (at the corner size 0.05 mm; at 20% that mesh stops short in Newton's method).
BULK_SIZE, GROWTH = 0.001, 0.25
# A free surface of a neo-Hookean solid creases when compressed below this stretch (Hong, Zhao and Suo 2009).
CREASE_STRETCH = 0.65
# *STATIC of the compressions: first increment, whole step, smallest and largest increment (fractions of the stroke).
COMPRESSION_STEP = "0.05, 1.0, 1e-6, 0.05"
# CalculiX expands an axisymmetric model into a 2-degree sector: its reactions are 1/180 of the whole ring's.
SECTOR = 180.0

GEO_3D = """SetFactory("OpenCASCADE");
Disk(1) = {{0, 0, 0, {r}, {r}}};
Mesh.CharacteristicLengthMax = {h};
Recombine Surface{{1}};
out[] = Extrude {{0, 0, {height}}} {{ Surface{{1}}; Layers{{{layers}}}; Recombine; }};
Physical Surface("bottom") = {{1}};
Physical Surface("top") = {{out[0]}};
Physical Volume("body") = {{out[1]}};
"""

# The (r, z) half section; points 2 and 3 of the rectangle are the rims (R, 0) and (R, H).
GEO_AXISYMMETRIC = """SetFactory("OpenCASCADE");
Rectangle(1) = {{0, 0, 0, {r}, {height}}};
Field[1] = Distance; Field[1].PointsList = {{2, 3}};
Field[2] = MathEval; Field[2].F = "Min({bulk}, Max({corner}, {growth} * F1))";
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6; Mesh.RecombineAll = 1; Mesh.RecombinationAlgorithm = 1;
Physical Surface("body") = {{1}};
"""


def gmsh_inp(folder, geo_text, dimension):
    geo = os.path.join(folder, "model.geo")
    with open(geo, "w") as f:
        f.write(geo_text)
    inp = os.path.join(folder, "model.inp")
    subprocess.run(["gmsh", f"-{dimension}", geo, "-order", "2", "-setnumber", "Mesh.SecondOrderIncomplete", "1",
                    "-setnumber", "Mesh.SaveGroupsOfNodes", "1", "-format", "inp", "-o", inp],
                   check=True, capture_output=True)
    return inp


def write_deck(path, nodes, elements, element_type, node_sets, boundary, step, time_points=None, print_side=False):
    """A CalculiX deck: the Ogden body, `boundary` (*BOUNDARY lines), the top set's total reaction printed."""
    with open(path, "w") as f:
        f.write("*NODE\n" + "".join(f"{n}, " + ", ".join(repr(c) for c in xyz) + "\n" for n, xyz in nodes.items()))
        f.write(f"*ELEMENT, TYPE={element_type}, ELSET=BODY\n")
        for index, element in enumerate(elements):
            ids = [str(index + 1)] + [str(n) for n in element]
            f.write(",\n".join(", ".join(ids[i:i + 15]) for i in range(0, len(ids), 15)) + "\n")
        for name, ids in node_sets.items():
            ids = sorted(set(ids))
            f.write(f"*NSET, NSET={name}\n" + "".join(", ".join(map(str, ids[i:i + 8])) + "\n"
                                                      for i in range(0, len(ids), 8)))
        f.write(f"*MATERIAL, NAME=SYLGARD\n*HYPERELASTIC, OGDEN, N=1\n{MU}, {ALPHA}, {D}\n")
        f.write("*SOLID SECTION, ELSET=BODY, MATERIAL=SYLGARD\n")
        if time_points:
            f.write("*TIME POINTS, NAME=T\n" + ", ".join(str(t) for t in time_points) + "\n")
        f.write(f"*STEP, NLGEOM, INC=1000\n*STATIC\n{step}\n*BOUNDARY\n{boundary}")
        f.write("*NODE PRINT, NSET=TOP, TOTALS=ONLY" + (", TIME POINTS=T" if time_points else "") + "\nRF\n")
        if print_side:
            f.write("*NODE PRINT, NSET=SIDE, TIME POINTS=T\nU\n")
        f.write("*END STEP\n")


def top_reactions(deck):
    """Runs CalculiX on `deck` (a path ending in .inp) and returns the top set's total reactions (fx, fy, fz),
    one per printed time, and whether CalculiX finished."""
    folder, name = os.path.split(deck[:-4])
    finished = subprocess.run(["ccx", "-i", name], cwd=folder, capture_output=True).returncode == 0
    text = open(deck[:-4] + ".dat").read()
    totals = re.findall(r"total force \(fx,fy,fz\) for set TOP and time\s+\S+\s*\n\s*\n?(.*)", text)
    return [tuple(float(v) for v in row.split()) for row in totals], finished


def compression_forces(deck, scale, component):
    """The top platen's compressive force (N) at each of FRACTIONS."""
    totals, finished = top_reactions(deck)
    if not finished or len(totals) != len(FRACTIONS):
        sys.exit(f"CalculiX stopped after {len(totals)} of {len(FRACTIONS)} compressions; see {deck[:-4]}.dat")
    return [-scale * row[component] for row in totals]


def run_3d(h):
    with tempfile.TemporaryDirectory() as folder:
        geo = GEO_3D.format(r=RADIUS, h=h, height=HEIGHT, layers=max(2, round(HEIGHT / h)))
        nodes, elements, sets = read_inp(gmsh_inp(folder, geo, 3), "C3D20")
        deck = os.path.join(folder, "compression.inp")
        write_deck(deck, nodes, elements, "C3D20R", {"BOTTOM": sets["bottom"], "TOP": sets["top"]},
                   f"BOTTOM, 1, 3\nTOP, 1, 2\nTOP, 3, 3, {-STROKE}\n", COMPRESSION_STEP, FRACTIONS)
        return len(nodes), len(elements), compression_forces(deck, 1.0, 2)


def counterclockwise(nodes, quad):
    """The 8-node quadrilateral numbered counterclockwise in the (r, z) plane, as CalculiX needs."""
    (x1, y1), (x2, y2), (x4, y4) = (nodes[quad[i]][:2] for i in (0, 1, 3))
    if (x2 - x1) * (y4 - y1) - (y2 - y1) * (x4 - x1) > 0:
        return quad
    return [quad[0], quad[3], quad[2], quad[1], quad[7], quad[6], quad[5], quad[4]]


def side_profile(deck, nodes, side):
    """At each compression, from the side's displacements in the .dat: the free side's least meridional stretch (it
    lies beside a singular rim, so it falls further as the corner is refined) and the side's nodes above the top
    platen's plane (how many, how far at most, and from how far under the rim)."""
    text = open(deck[:-4] + ".dat").read()
    blocks = re.split(r"displacements \(vx,vy,vz\) for set SIDE and time\s+(\S+)", text)
    side = sorted(side, key=lambda n: -nodes[n][1])
    for time, block in zip(blocks[1::2], blocks[2::2]):
        u = {}
        for line in block.strip().splitlines():
            values = line.split()
            if len(values) < 3 or not values[0].isdigit():
                break
            u[int(values[0])] = (float(values[1]), float(values[2]))
        moved = [(nodes[n][1], nodes[n][0] + u[n][0], nodes[n][1] + u[n][1]) for n in side]
        least = min(math.hypot(a[1] - b[1], a[2] - b[2]) / (a[0] - b[0]) for a, b in zip(moved, moved[1:]))
        platen = HEIGHT - float(time) * STROKE
        above = [(z - platen, HEIGHT - z0) for z0, _, z in moved if z > platen + 1e-12]
        print(f"  {100 * 0.2 * float(time):.0f}%: least meridional stretch of the side {least:.3f}"
              f"{' (below ' + str(CREASE_STRETCH) + ')' if least < CREASE_STRETCH else ''}; {len(above)} side nodes "
              f"above the top platen, by {1e3 * max(above, default=(0.0, 0.0))[0]:.3f} mm at most, from "
              f"{1e3 * max((d for _, d in above), default=0.0):.2f} mm under the rim", flush=True)


def run_axisymmetric(corner, surface=False):
    with tempfile.TemporaryDirectory() as folder:
        geo = GEO_AXISYMMETRIC.format(r=RADIUS, height=HEIGHT, bulk=BULK_SIZE, corner=corner, growth=GROWTH)
        nodes, elements, _ = read_inp(gmsh_inp(folder, geo, 2), "CPS8")
        elements = [counterclockwise(nodes, quad) for quad in elements]
        used = {n for quad in elements for n in quad}
        nodes = {n: xyz[:2] for n, xyz in nodes.items() if n in used}
        at = lambda axis, value: [n for n, xyz in nodes.items() if abs(xyz[axis] - value) < 1e-9]
        deck = os.path.join(folder, "compression.inp")
        sets = {"BOTTOM": at(1, 0.0), "TOP": at(1, HEIGHT), "AXIS": at(0, 0.0)}
        if surface:
            sets["SIDE"] = at(0, RADIUS)
        write_deck(deck, nodes, elements, "CAX8", sets, f"BOTTOM, 1, 2\nAXIS, 1, 1\nTOP, 1, 1\nTOP, 2, 2, {-STROKE}\n",
                   COMPRESSION_STEP, FRACTIONS, print_side=surface)
        forces = compression_forces(deck, SECTOR, 1)
        if surface:
            side_profile(deck, nodes, sets["SIDE"])
        return len(nodes), len(elements), forces


# One 20-node hexahedron (CalculiX's node order: 8 corners, then the 12 edge midpoints) for the uniaxial check.
CUBE_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]
# One 8-node quadrilateral (4 corners, then the 4 edge midpoints) for the axisymmetric uniaxial check.
SQUARE_CORNERS = [(0, 0), (1, 0), (1, 1), (0, 1)]
SQUARE_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0)]


def uniaxial(axisymmetric, side=0.01, stretch=0.8):
    """Nominal stress of a cube (or, axisymmetric, a cylinder of radius and height `side`) compressed to `stretch`
    with frictionless ends (homogeneous), by CalculiX."""
    corners, edges = (SQUARE_CORNERS, SQUARE_EDGES) if axisymmetric else (CUBE_CORNERS, CUBE_EDGES)
    points = [tuple(side * c for c in corner) for corner in corners]
    points += [tuple((a + b) / 2 for a, b in zip(points[i], points[j])) for i, j in edges]
    axial = 1 if axisymmetric else 2
    members = lambda axis, value: [i + 1 for i, p in enumerate(points) if abs(p[axis] - value) < 1e-12]
    sets = {"BOTTOM": members(axial, 0.0), "TOP": members(axial, side), "XZERO": members(0, 0.0)}
    boundary = f"BOTTOM, {axial + 1}, {axial + 1}\nXZERO, 1, 1\nTOP, {axial + 1}, {axial + 1}, {-(1 - stretch) * side}\n"
    if not axisymmetric:
        sets["YZERO"] = members(1, 0.0)
        boundary += "YZERO, 2, 2\n"
    with tempfile.TemporaryDirectory() as folder:
        deck = os.path.join(folder, "uniaxial.inp")
        write_deck(deck, {i + 1: p for i, p in enumerate(points)}, [list(range(1, len(points) + 1))],
                   "CAX8" if axisymmetric else "C3D20R", sets, boundary, "0.05, 1.0, 1e-6, 0.1")
        totals, _ = top_reactions(deck)
        area = math.pi * side ** 2 if axisymmetric else side ** 2
        return (SECTOR if axisymmetric else 1.0) * totals[-1][axial] / area


def check_setup(axisymmetric):
    """The cross-check of the setup (element, Ogden parameters, reaction totals, the axisymmetric sector's
    scale): the homogeneous uniaxial case against its closed form (scripts/uniaxial_exact.py; the scene
    uniaxial_cube_ogden.json's -649.5651 Pa)."""
    from uniaxial_exact import top_force
    exact = top_force(MU, ALPHA, D, 0.8, 0.01) / 1e-4
    calculix = uniaxial(axisymmetric)
    print(f"uniaxial {'cylinder (CAX8)' if axisymmetric else 'cube (C3D20R)'} at stretch 0.8: CalculiX "
          f"{calculix:.7g} Pa, exact {exact:.7g} Pa, relative difference {abs(calculix / exact - 1):.1e}", flush=True)
    assert abs(calculix / exact - 1) < 1e-6, (calculix, exact)


def main():
    output = sys.argv[1]
    flags = {a for a in sys.argv[2:] if a.startswith("--")}
    check, axisymmetric, surface = "--check" in flags, "--axisymmetric" in flags, "--surface" in flags
    if surface and not axisymmetric:
        sys.exit("--surface reads the axisymmetric section's side: add --axisymmetric")
    sizes = [float(s) for s in sys.argv[2:] if not s.startswith("--")]
    sizes = sizes or ([0.4, 0.2, 0.1, 0.05] if axisymmetric else [3.0, 2.0, 1.5])
    check_setup(axisymmetric)
    rows = []
    for size in sizes:
        nodes, elements, forces = run_axisymmetric(size * 1e-3, surface) if axisymmetric else run_3d(size * 1e-3)
        rows.append([size, nodes, elements] + forces)
        print(f"{'corner size' if axisymmetric else 'h'} = {size} mm: {nodes} nodes, {elements} "
              f"{'CAX8' if axisymmetric else 'C3D20R'}, top force at 5/10/15/20%: "
              + ", ".join(f"{f:.5g}" for f in forces) + " N", flush=True)
    if check:  # the smoke test's physics: the force grows with compression, stiffening (convex), positive
        for row in rows:
            forces = row[3:]
            assert all(0 < a < b for a, b in zip(forces, forces[1:])), forces
            assert forces[1] - forces[0] < forces[2] - forces[1] < forces[3] - forces[2], forces
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    with open(output, "w", newline="") as f:
        writer = csv.writer(f)
        size_column = "corner_size_mm" if axisymmetric else "element_size_mm"
        writer.writerow([size_column, "nodes", "elements"] + [f"force_N_at_{round(100 * 0.2 * t)}pct" for t in FRACTIONS])
        writer.writerows([row[:3] + [f"{f:.7g}" for f in row[3:]] for row in rows])


if __name__ == "__main__":
    main()
