"""Reading Abaqus .inp meshes (Gmsh's export, `mtled mesh`) for the scripts: Debian's python3, no other package."""
import re
import sys


NODES_PER_ELEMENT = {"C3D4": 4, "C3D20": 20, "CPS8": 8}


def read_inp(path, element_kind):
    """Nodes ({id: coordinates}), the elements of `element_kind` (C3D4, C3D20, CPS8) and the node sets of an Abaqus
    file (Gmsh's export, `mtled mesh`); other elements of the same dimension (a triangle left by a recombination) are
    refused."""
    nodes, elements, sets, pending = {}, [], {}, []
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
            elif keyword.startswith("*ELEMENT"):
                kind = re.search(r"TYPE=(\w+)", keyword).group(1)
                if kind == element_kind:
                    section = "element"
                elif kind[:3] == element_kind[:3]:
                    sys.exit(f"{path}: Gmsh wrote {kind} elements, expected only {element_kind}")
            elif keyword.startswith("*NSET"):
                section, name = "nset", re.search(r"NSET=([^,\s]+)", line, re.I).group(1).lower()
                sets[name] = []
            continue
        values = [v.strip() for v in line.split(",") if v.strip()]
        if section == "node":
            nodes[int(values[0])] = tuple(float(v) for v in values[1:])
        elif section == "element":  # an element's line may continue on the next (Gmsh writes 15 numbers a line)
            pending.extend(int(v) for v in values)
            if len(pending) == 1 + NODES_PER_ELEMENT[element_kind]:
                elements.append(pending[1:])
                pending = []
        elif section == "nset":
            sets[name].extend(int(v) for v in values)
    return nodes, elements, sets
