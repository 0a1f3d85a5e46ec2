#!/usr/bin/env python3
"""An independent finite-element reference for the semi-confined compression (share/scenes/
compression_semiconfined.json): CalculiX (Debian's calculix-ccx) with quadratic, reduced-integration hexahedra
(C3D20R), meshed by Gmsh, geometric nonlinearity, the same Ogden law and parameters.

The cylinder (30 mm across, 17 mm high) is a quadrilateral mesh of the disc extruded in layers, so every
element is a hexahedron; both faces are bonded to the platens (bottom fixed, top moved down, its x and y
held), the side free. CalculiX's Ogden law with N = 1 is mtled's: W = (2 mu / alpha^2)(sum_i lambdabar_i^alpha
- 3) + (1/D)(J - 1)^2 (lambdabar: the isochoric stretches). The top platen's total reaction is printed at 5,
10, 15 and 20% compression, on each refinement (element sizes below), into a CSV. First it checks the setup on
the homogeneous uniaxial case (one element, frictionless ends) against the closed form.

Usage: semiconfined_calculix.py OUTPUT.csv [SIZE_MM ...] [--check]   (default sizes 3 2 1.5 mm; needs gmsh and ccx;
--check asserts that the force grows with compression, ever faster)
"""
import csv
import os
import re
import subprocess
import sys
import tempfile

MU, ALPHA, D = 722.0, -1.3, 5.57738e-5  # the scene's Ogden parameters (Pa, 1, 1/Pa)
RADIUS, HEIGHT, STROKE = 0.015, 0.017, 0.0034  # m: 20% nominal compression
FRACTIONS = (0.25, 0.5, 0.75, 1.0)  # of the stroke: 5, 10, 15, 20%

GEO = """SetFactory("OpenCASCADE");
Disk(1) = {{0, 0, 0, {r}, {r}}};
Mesh.CharacteristicLengthMax = {h};
Recombine Surface{{1}};
out[] = Extrude {{0, 0, {height}}} {{ Surface{{1}}; Layers{{{layers}}}; Recombine; }};
Physical Surface("bottom") = {{1}};
Physical Surface("top") = {{out[0]}};
Physical Volume("body") = {{out[1]}};
"""


def mesh(folder, h):
    geo = os.path.join(folder, "cylinder.geo")
    with open(geo, "w") as f:
        f.write(GEO.format(r=RADIUS, h=h, height=HEIGHT, layers=max(2, round(HEIGHT / h))))
    inp = os.path.join(folder, "cylinder.inp")
    subprocess.run(["gmsh", "-3", geo, "-order", "2", "-setnumber", "Mesh.SecondOrderIncomplete", "1",
                    "-setnumber", "Mesh.SaveGroupsOfNodes", "1", "-format", "inp", "-o", inp],
                   check=True, capture_output=True)
    return inp


def read_gmsh_inp(path):
    """Nodes, the C3D20 elements and the node sets of Gmsh's Abaqus export."""
    nodes, elements, sets = [], [], {}
    section, name = None, None
    for line in open(path):
        line = line.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            keyword = line.upper()
            section, name = None, None
            if keyword.startswith("*NODE") and not keyword.startswith("*NODE PRINT"):
                section = "node"
            elif keyword.startswith("*ELEMENT") and "C3D20" in keyword:
                section = "element"
            elif keyword.startswith("*NSET"):
                section, name = "nset", re.search(r"NSET=([^,\s]+)", line, re.I).group(1).lower()
                sets[name] = []
            continue
        values = [v for v in line.split(",") if v.strip()]
        if section == "node":
            nodes.append(line)
        elif section == "element":
            elements.append(line)
        elif section == "nset":
            sets[name].extend(int(v) for v in values)
    return nodes, elements, sets


def write_ccx(folder, nodes, elements, sets):
    deck = os.path.join(folder, "compression.inp")
    with open(deck, "w") as f:
        f.write("*NODE\n" + "\n".join(nodes) + "\n")
        f.write("*ELEMENT, TYPE=C3D20R, ELSET=BODY\n" + "\n".join(elements) + "\n")
        for name in ("bottom", "top"):
            f.write(f"*NSET, NSET={name.upper()}\n")
            ids = sorted(set(sets[name]))
            for i in range(0, len(ids), 8):
                f.write(", ".join(str(v) for v in ids[i:i + 8]) + "\n")
        f.write("*MATERIAL, NAME=SYLGARD\n*HYPERELASTIC, OGDEN, N=1\n")
        f.write(f"{MU}, {ALPHA}, {D}\n")
        f.write("*SOLID SECTION, ELSET=BODY, MATERIAL=SYLGARD\n")
        f.write("*TIME POINTS, NAME=T\n" + ", ".join(str(t) for t in FRACTIONS) + "\n")
        f.write("*STEP, NLGEOM, INC=1000\n*STATIC\n0.05, 1.0, 1e-6, 0.05\n")
        f.write(f"*BOUNDARY\nBOTTOM, 1, 3\nTOP, 1, 2\nTOP, 3, 3, {-STROKE}\n")
        f.write("*NODE PRINT, NSET=TOP, TOTALS=ONLY, TIME POINTS=T\nRF\n*END STEP\n")
    return deck


def run(h):
    with tempfile.TemporaryDirectory() as folder:
        nodes, elements, sets = read_gmsh_inp(mesh(folder, h))
        deck = write_ccx(folder, nodes, elements, sets)
        subprocess.run(["ccx", "-i", deck[:-4]], cwd=folder, check=True, capture_output=True)
        text = open(deck[:-4] + ".dat").read()
        forces = [float(m.group(1).split()[2]) for m in
                  re.finditer(r"total force \(fx,fy,fz\) for set TOP and time\s+\S+\s*\n\s*\n?(.*)", text)]
        if len(forces) != len(FRACTIONS):
            sys.exit(f"CalculiX printed {len(forces)} totals, expected {len(FRACTIONS)}:\n{text[-2000:]}")
        return len(nodes), len(elements), [-f for f in forces]


# One 20-node hexahedron (CalculiX's node order: 8 corners, then the 12 edge midpoints) for the uniaxial check.
CUBE_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_EDGES = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]


def uniaxial(side=0.01, stretch=0.8):
    """Nominal stress of a cube compressed to `stretch` with frictionless ends (homogeneous), by CalculiX."""
    points = [tuple(side * c for c in corner) for corner in CUBE_CORNERS]
    points += [tuple((a + b) / 2 for a, b in zip(points[i], points[j])) for i, j in CUBE_EDGES]
    with tempfile.TemporaryDirectory() as folder:
        deck = os.path.join(folder, "uniaxial.inp")
        with open(deck, "w") as f:
            f.write("*NODE\n" + "".join(f"{i + 1}, {x}, {y}, {z}\n" for i, (x, y, z) in enumerate(points)))
            ids = list(range(1, 21))
            f.write("*ELEMENT, TYPE=C3D20R, ELSET=BODY\n1, " + ", ".join(map(str, ids[:15])) + ",\n"
                    + ", ".join(map(str, ids[15:])) + "\n")
            for name, axis, value in (("BOTTOM", 2, 0.0), ("TOP", 2, side), ("XZERO", 0, 0.0), ("YZERO", 1, 0.0)):
                members = [str(i + 1) for i, p in enumerate(points) if abs(p[axis] - value) < 1e-12]
                f.write(f"*NSET, NSET={name}\n" + ", ".join(members) + "\n")
            f.write(f"*MATERIAL, NAME=SYLGARD\n*HYPERELASTIC, OGDEN, N=1\n{MU}, {ALPHA}, {D}\n")
            f.write("*SOLID SECTION, ELSET=BODY, MATERIAL=SYLGARD\n")
            f.write("*STEP, NLGEOM, INC=1000\n*STATIC\n0.05, 1.0, 1e-6, 0.1\n")
            f.write(f"*BOUNDARY\nBOTTOM, 3, 3\nXZERO, 1, 1\nYZERO, 2, 2\nTOP, 3, 3, {-(1 - stretch) * side}\n")
            f.write("*NODE PRINT, NSET=TOP, TOTALS=ONLY\nRF\n*END STEP\n")
        subprocess.run(["ccx", "-i", deck[:-4]], cwd=folder, check=True, capture_output=True)
        text = open(deck[:-4] + ".dat").read()
        totals = re.findall(r"total force \(fx,fy,fz\) for set TOP and time\s+\S+\s*\n\s*\n?(.*)", text)
        return float(totals[-1].split()[2]) / side ** 2


def main():
    output = sys.argv[1]
    check = "--check" in sys.argv[2:]
    sizes = [float(s) for s in sys.argv[2:] if s != "--check"] or [3.0, 2.0, 1.5]
    # The cross-check of the setup (element, Ogden parameters, reaction totals): the homogeneous uniaxial case
    # against its closed form (scripts/uniaxial_exact.py; the scene uniaxial_cube_ogden.json's -649.5651 Pa).
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    from uniaxial_exact import top_force
    exact = top_force(MU, ALPHA, D, 0.8, 0.01) / 1e-4
    calculix = uniaxial()
    print(f"uniaxial cube at stretch 0.8: CalculiX {calculix:.7g} Pa, exact {exact:.7g} Pa, "
          f"relative difference {abs(calculix / exact - 1):.1e}", flush=True)
    assert abs(calculix / exact - 1) < 1e-6, (calculix, exact)
    rows = []
    for size in sizes:
        nodes, elements, forces = run(size * 1e-3)
        rows.append([size, nodes, elements] + forces)
        print(f"h = {size} mm: {nodes} nodes, {elements} C3D20R, top force at 5/10/15/20%: "
              + ", ".join(f"{f:.5g}" for f in forces) + " N", flush=True)
    if check:  # the smoke test's physics: the force grows with compression, stiffening (convex), positive
        for row in rows:
            forces = row[3:]
            assert all(0 < a < b for a, b in zip(forces, forces[1:])), forces
            assert forces[1] - forces[0] < forces[2] - forces[1] < forces[3] - forces[2], forces
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    with open(output, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["element_size_mm", "nodes", "elements"] + [f"force_N_at_{round(100 * 0.2 * t)}pct" for t in FRACTIONS])
        writer.writerows(rows)


if __name__ == "__main__":
    main()
