#!/usr/bin/env python3
"""Checks the second-order meshes of this folder through the gmsh Python API (gmsh.open):

  * the element types of each file (top dimension and boundary) are the intended ones;
  * the physical groups (name, dimension, tag) are the intended ones;
  * ring_* and cylinder_*: every node of the Inner / Outer groups' elements (corners and
    midside / face nodes) lies on r = 1 / r = 2 (max |r - R| printed, must be < 1e-12);
  * hertz_3d_*: every node of the Gamma3 elements lies on z = 0 (to 1e-12), in 0 <= x, y <= 0.16;
  * every edge node of a boundary facet is at its edge's midpoint (of the arc in (r, θ, z) on
    r = 1 / r = 2, else of the segment), every face node of a quadrangle on Inner / Outer at its
    centre, to 1e-8 (also checks the facets' high-order node order);
  * every cell has det J > 0 at its Gauss points (skipped for mixed_order.msh);
  * every boundary facet is a face of exactly one cell and its corner node order gives the
    outward normal (information: the count of inward facets is printed; only checked for the
    ring, rectangle and cylinder files);
  * the measure (area / volume, by Gauss quadrature of det J) against the exact one.

    python3 check.py             # every *.msh here
    python3 check.py a.msh ...   # those files
Exit status 1 if a check fails.
"""
import glob
import math
import os
import sys

import gmsh

NAMES = {1: "line2", 8: "line3", 2: "tri3", 9: "tri6", 3: "quad4", 10: "quad9", 16: "quad8",
         4: "tet4", 11: "tet10", 5: "hex8", 12: "hex27", 17: "hex20", 6: "prism6", 13: "prism18",
         18: "prism15", 7: "pyr5", 14: "pyr14", 19: "pyr13", 15: "point"}
# number of corner nodes of each type
CORNERS = {1: 2, 8: 2, 2: 3, 9: 3, 3: 4, 10: 4, 16: 4, 4: 4, 11: 4, 5: 8, 12: 8, 17: 8,
           6: 6, 13: 6, 18: 6, 7: 5, 14: 5, 19: 5}

RING = {(1, 1): "Inner", (1, 2): "Outer", (1, 3): "SymX", (1, 4): "SymY", (2, 5): "Omega"}
CYL = {(2, 1): "Inner", (2, 2): "Outer", (2, 3): "SymX", (2, 4): "SymY", (2, 6): "Bottom",
       (2, 7): "Top", (3, 5): "Omega"}
RECT = {(1, 1): "Gamma1", (1, 2): "Gamma2", (1, 3): "Gamma3", (1, 4): "Gamma2_top",
        (2, 5): "Omega"}
PYR = {(2, 1): "Gamma1", (2, 2): "Gamma2", (2, 3): "Gamma3", (3, 5): "Omega"}
MIXED = {(1, 1): "Gamma1", (1, 2): "Gamma2", (1, 3): "Gamma3", (2, 5): "Omega"}
HERTZ2D = {(1, 3): "Gamma3", (1, 4): "Symmetry", (1, 5): "Base", (1, 6): "Free", (2, 7): "Omega"}
HERTZ3D = {(2, 3): "Gamma3", (2, 4): "SymX", (2, 5): "SymY", (2, 6): "Base", (2, 7): "Free",
           (3, 8): "Omega"}

RING_AREA = 0.75 * math.pi
# file prefix -> (top-dim types, boundary types, groups, exact measure)
EXPECT = {
    "ring_p1": ({2}, {1}, RING, RING_AREA),
    "ring_q1": ({3}, {1}, RING, RING_AREA),
    "ring_p2": ({9}, {8}, RING, RING_AREA),
    "ring_q9": ({10}, {8}, RING, RING_AREA),
    "ring_q8": ({16}, {8}, RING, RING_AREA),
    "cylinder_tet10": ({11}, {9}, CYL, 0.5 * RING_AREA),
    "cylinder_hex27": ({12}, {10}, CYL, 0.5 * RING_AREA),
    "cylinder_hex20": ({17}, {16}, CYL, 0.5 * RING_AREA),
    "cylinder_prism18": ({13}, {9, 10}, CYL, 0.5 * RING_AREA),
    "cylinder_prism15": ({18}, {9, 16}, CYL, 0.5 * RING_AREA),
    "rect_q9": ({10}, {8}, RECT, 2.0),
    "rect_p2": ({9}, {8}, RECT, 2.0),
    "pyramid13": ({11, 17, 19}, {9, 16}, PYR, 0.5),
    "pyramid14": ({11, 12, 14}, {9, 10}, PYR, 0.5),
    "mixed_order": ({2, 9}, {1, 8}, MIXED, 2.0),
    "hertz_2d_p2": ({9}, {8}, HERTZ2D, 2.0 * 2.0),
    "hertz_3d_tet10": ({11}, {9}, HERTZ3D, 1.5 ** 3),
}

# faces (corner indices, gmsh local numbering) of the cells, to find the cell of a boundary facet
FACES = {
    2: [(0, 1), (1, 2), (2, 0)],
    3: [(0, 1), (1, 2), (2, 3), (3, 0)],
    4: [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)],
    5: [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
    6: [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    7: [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
}
FIRST = {2: 2, 9: 2, 3: 3, 10: 3, 16: 3, 4: 4, 11: 4, 5: 5, 12: 5, 17: 5, 6: 6, 13: 6, 18: 6,
         7: 7, 14: 7, 19: 7}


# edge nodes of the boundary facets: ((corner i, corner j), node index)
EDGES = {
    8: [((0, 1), 2)],
    9: [((0, 1), 3), ((1, 2), 4), ((2, 0), 5)],
    10: [((0, 1), 4), ((1, 2), 5), ((2, 3), 6), ((3, 0), 7)],
    16: [((0, 1), 4), ((1, 2), 5), ((2, 3), 6), ((3, 0), 7)],
}


def midpoint(ps, curved):
    """The centre of the points ps: in (r, θ, z) if curved and all on one circle r = 1 or r = 2,
    else in (x, y, z)."""
    rs = [math.hypot(p[0], p[1]) for p in ps]
    for R in (1.0, 2.0):
        if curved and all(abs(r - R) < 1e-9 for r in rs):
            th = sum(math.atan2(p[1], p[0]) for p in ps) / len(ps)
            return [R * math.cos(th), R * math.sin(th), sum(p[2] for p in ps) / len(ps)]
    return [sum(p[i] for p in ps) / len(ps) for i in range(3)]


def dist(a, b):
    return math.sqrt(sum((a[i] - b[i]) ** 2 for i in range(3)))


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def check(path):
    name = os.path.basename(path)
    key = next((k for k in sorted(EXPECT, key=len, reverse=True) if name.startswith(k)), None)
    errors = []
    if key is None:
        return [f"{name}: no expectations in check.py"], None
    top_want, bnd_want, groups_want, measure_want = EXPECT[key]
    if key == "mixed_order":
        return check_mixed(path, top_want, bnd_want)
    curved = key.startswith(("ring", "cylinder"))
    gmsh.clear()
    gmsh.open(path)
    dim = gmsh.model.getDimension()
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = {int(t): coords[3 * i:3 * i + 3] for i, t in enumerate(tags)}
    top = set(gmsh.model.mesh.getElementTypes(dim))
    bnd = set(gmsh.model.mesh.getElementTypes(dim - 1))
    if top != top_want:
        errors.append(f"cells {sorted(top)}, want {sorted(top_want)}")
    if bnd != bnd_want:
        errors.append(f"facets {sorted(bnd)}, want {sorted(bnd_want)}")
    groups = {(d, t): gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
    if groups != groups_want:
        errors.append(f"groups {groups}, want {groups_want}")

    # cells, their count per type, det J > 0, measure
    cells = []  # (type, node tags)
    counts = {}
    measure = 0.0
    for t in sorted(top):
        etags, enodes = gmsh.model.mesh.getElementsByType(t)
        nn = len(enodes) // len(etags)
        counts[NAMES[t]] = len(etags)
        cells += [(t, [int(v) for v in enodes[k * nn:(k + 1) * nn]]) for k in range(len(etags))]
        pts, wts = gmsh.model.mesh.getIntegrationPoints(t, "Gauss6")
        _, dets, _ = gmsh.model.mesh.getJacobians(t, pts)
        npts = len(wts)
        if key != "mixed_order" and min(dets) <= 0:
            errors.append(f"{NAMES[t]}: det J = {min(dets):.3g} <= 0")
        measure += sum(dets[k] * wts[k % npts] for k in range(len(dets)))
    used = {v for _, ns in cells for v in ns}
    if used != set(xyz):
        errors.append(f"{len(set(xyz) - used)} nodes in no cell")

    # boundary facets: each a face of one cell, outward normal
    n2c = {}
    for c, (_, ns) in enumerate(cells):
        for v in ns:
            n2c.setdefault(v, []).append(c)
    inward = {}
    nfacets = {}
    for (d, g), gname in groups.items():
        if d != dim - 1:
            continue
        for ent in gmsh.model.getEntitiesForPhysicalGroup(d, g):
            for t in gmsh.model.mesh.getElementTypes(d, ent):
                etags, enodes = gmsh.model.mesh.getElementsByType(t, ent)
                nn = len(enodes) // len(etags)
                nc = CORNERS[t]
                for k in range(len(etags)):
                    f = [int(v) for v in enodes[k * nn:k * nn + nc]]
                    cand = set(n2c.get(f[0], []))
                    for v in f[1:]:
                        cand &= set(n2c.get(v, []))
                    # a cell has the facet as a face if the corners match one of its faces
                    owners = []
                    for c in cand:
                        ct, cn = cells[c]
                        fs = {frozenset(cn[i] for i in face) for face in FACES[FIRST[ct]]}
                        if frozenset(f) in fs:
                            owners.append(c)
                    if len(owners) != 1:
                        errors.append(f"{gname}: a facet is a face of {len(owners)} cells")
                        continue
                    ct, cn = cells[owners[0]]
                    cc = [sum(xyz[v][i] for v in cn[:CORNERS[ct]]) / CORNERS[ct] for i in range(3)]
                    fc = [sum(xyz[v][i] for v in f) / nc for i in range(3)]
                    p = [xyz[v] for v in f]
                    if dim == 2:
                        e = sub(p[1], p[0])
                        nrm = [e[1], -e[0], 0.0]
                    elif nc == 3:
                        nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]))
                    else:
                        nrm = cross(sub(p[2], p[0]), sub(p[3], p[1]))
                    nfacets[gname] = nfacets.get(gname, 0) + 1
                    if dot(nrm, sub(fc, cc)) <= 0:
                        inward[gname] = inward.get(gname, 0) + 1
    if key not in ("mixed_order", "pyramid13", "pyramid14") and inward:
        errors.append(f"inward facets {inward}")

    # curved boundaries on the circles: every node (corner, midside, face) of every element of
    # the Inner / Outer groups
    dev = {}
    for (d, g), gname in groups.items():
        if d == dim - 1 and gname in ("Inner", "Outer"):
            R = 1.0 if gname == "Inner" else 2.0
            nodes = set()
            for ent in gmsh.model.getEntitiesForPhysicalGroup(d, g):
                for t in gmsh.model.mesh.getElementTypes(d, ent):
                    nodes.update(int(v) for v in gmsh.model.mesh.getElementsByType(t, ent)[1])
            dev[gname] = max(abs(math.hypot(xyz[v][0], xyz[v][1]) - R) for v in nodes)
            if dev[gname] >= 1e-12:
                errors.append(f"{gname}: a node {dev[gname]:.3g} off r = {R}")

    # hertz_3d_*: every node of the Gamma3 elements on z = 0 (to 1e-12), in 0 <= x, y <= 0.16
    if key == "hertz_3d_tet10" and (2, 3) in groups:
        nodes = set()
        for ent in gmsh.model.getEntitiesForPhysicalGroup(2, 3):
            for t in gmsh.model.mesh.getElementTypes(2, ent):
                nodes.update(int(v) for v in gmsh.model.mesh.getElementsByType(t, ent)[1])
        if max(abs(xyz[v][2]) for v in nodes) >= 1e-12 or not all(
                0 <= xyz[v][i] <= 0.16 for v in nodes for i in (0, 1)):
            errors.append("Gamma3: a node off z = 0 or outside 0 <= x, y <= 0.16")

    # high-order nodes where they belong: every edge node of a boundary facet at its edge's midpoint
    # (on an edge with both ends on r = 1 or both on r = 2, the midpoint of the arc in (r, θ, z);
    # else the straight midpoint), every face node of a quadrangle on Inner / Outer at the centre
    # of the patch in (θ, z). This also checks that the high-order nodes are listed in gmsh's order.
    mid = 0.0
    for (d, g), gname in groups.items():
        if d != dim - 1:
            continue
        for ent in gmsh.model.getEntitiesForPhysicalGroup(d, g):
            for t in gmsh.model.mesh.getElementTypes(d, ent):
                if t not in EDGES:
                    continue
                etags, enodes = gmsh.model.mesh.getElementsByType(t, ent)
                nn = len(enodes) // len(etags)
                for k in range(len(etags)):
                    f = [xyz[int(v)] for v in enodes[k * nn:(k + 1) * nn]]
                    for (i, j), m in EDGES[t]:
                        mid = max(mid, dist(f[m], midpoint([f[i], f[j]], curved)))
                    if t == 10 and gname in ("Inner", "Outer"):
                        mid = max(mid, dist(f[8], midpoint(f[:4], curved)))
    # (1e-8, not 1e-12: gmsh spaces the vertices of a transfinite arc equally in angle only to
    # ~2e-9 rad, and the midside node is at the curve parameter's midpoint, not quite at the mean
    # of the corners' atan2 angles; its radius is exact)
    if mid >= 1e-8:
        errors.append(f"a high-order node {mid:.3g} off its place")

    info = {
        "mid": mid,
        "nodes": len(xyz),
        "cells": counts,
        "facets": {NAMES[t]: len(gmsh.model.mesh.getElementsByType(t)[0]) for t in sorted(bnd)},
        "dev": dev,
        "measure_err": abs(measure - measure_want) / measure_want,
        "inward": inward,
        "size": os.path.getsize(path),
    }
    return [f"{name}: {e}" for e in errors], info


def check_mixed(path, top_want, bnd_want):
    """mixed_order.msh is parsed as text: gmsh reads it (it is valid MSH 4.1) but keeps only one
    element type per entity, and its API then misbehaves on the other type."""
    name = os.path.basename(path)
    lines = open(path).read().split("\n")
    i = lines.index("$Elements") + 1
    nblocks = int(lines[i].split()[0])
    i += 1
    types = {1: set(), 2: set()}
    counts = {}
    for _ in range(nblocks):
        d, _, t, n = map(int, lines[i].split())
        types[d].add(t)
        counts[NAMES[t]] = counts.get(NAMES[t], 0) + n
        i += n + 1
    errors = []
    if types[2] != top_want:
        errors.append(f"cells {sorted(types[2])}, want {sorted(top_want)}")
    if types[1] != bnd_want:
        errors.append(f"facets {sorted(types[1])}, want {sorted(bnd_want)}")
    i = lines.index("$Nodes") + 1
    info = {"nodes": int(lines[i].split()[1]), "cells": counts, "facets": {}, "dev": {},
            "measure_err": 0.0, "mid": 0.0, "inward": {}, "size": os.path.getsize(path)}
    return [f"{name}: {e}" for e in errors], info


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    files = sys.argv[1:] or sorted(glob.glob(os.path.join(here, "*.msh")))
    gmsh.initialize()
    gmsh.option.setNumber("General.Verbosity", 0)
    bad = []
    for f in files:
        errs, info = check(f)
        status = "FAILED" if errs else "OK"
        if info:
            dev = " ".join(f"{k} {v:.1e}" for k, v in info["dev"].items())
            print(f"{status} {os.path.basename(f)}: {info['size']} bytes, {info['nodes']} nodes, "
                  f"cells {info['cells']}, facets {info['facets']}"
                  + (f", max |r - R|: {dev}" if dev else "")
                  + f", max high-order node off place {info['mid']:.1e}"
                  + f", measure rel. error {info['measure_err']:.1e}"
                  + (f", inward facets {info['inward']}" if info["inward"] else ""))
        for e in errs:
            print("  ERROR", e)
        bad += errs
    gmsh.finalize()
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
