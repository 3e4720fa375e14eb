#!/usr/bin/env python3
"""Checks the gmsh meshes of this folder the way hvi needs them (MSH 4.1 ASCII, parsed here
directly, not through gmsh, so it checks the file itself):

  * only first-order elements (points, 2-node lines, 3-node triangles, 4-node quadrangles,
    4-node tetrahedra, 8-node hexahedra, 6-node prisms, 5-node pyramids);
  * every cell of the top dimension (the body) has positive orientation in gmsh's node order:
      tetrahedron  (x1 - x0) x (x2 - x0) . (x3 - x0) > 0,
      hexahedron   det J > 0 at all 8 corners (and the centre) of the trilinear map from the
                   reference corners (-1,-1,-1), (1,-1,-1), (1,1,-1), (-1,1,-1), (-1,-1,1),
                   (1,-1,1), (1,1,1), (-1,1,1),
      prism        det J > 0 at its 6 corners (triangle (1 - r - s, r, s) times segment (1 -+ t)/2),
      pyramid      det J > 0 at its 4 base corners and the base centre (its det J depends only on
                   (r, s)/(1 - t): hvi's rational basis, docs/method.md section 8.1),      triangle / quadrangle (2D files)  counter-clockwise: every corner turns left;
  * every element of every physical group of dimension top - 1 (surfaces in 3D, curves in 2D)
    is a face of exactly one body cell, i.e. lies on the boundary;
  * the boundary groups together cover the whole boundary (a face in no group is reported:
    gmsh saves only elements of physical groups, so such a face could not be loaded);
  * the physical group "Omega" of the top dimension holds every body cell, and every node is a
    node of some body cell.
It also reports, per boundary group, how many of its faces have their node order's normal
pointing out of the body (information only: nothing here requires a particular facet order).

With --same-xy 3D.msh=2D.msh (repeatable) it checks that every z layer of the 3D mesh has exactly
the nodes of the 2D mesh in (x, y); by default slab_q1_hN_*.msh is compared with rect_q1_hN.msh.

    python3 meshes/check_orientation.py                 # every *.msh in meshes/ (4.1 ASCII only)
    python3 meshes/check_orientation.py a.msh b.msh     # those files

Exit status 1 if any check fails.
"""
import glob
import os
import re
import sys

# gmsh element type -> (name, dimension, number of nodes); first order only.
TYPES = {
    15: ("point", 0, 1),
    1: ("line", 1, 2),
    2: ("triangle", 2, 3),
    3: ("quadrangle", 2, 4),
    4: ("tetrahedron", 3, 4),
    5: ("hexahedron", 3, 8),
    6: ("prism", 3, 6),
    7: ("pyramid", 3, 5),
}
# Faces (gmsh's local numbering) of the cells of each type; of lines the end points.
FACES = {
    1: [(0,), (1,)],
    2: [(0, 1), (1, 2), (2, 0)],
    3: [(0, 1), (1, 2), (2, 3), (3, 0)],
    4: [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)],
    5: [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
    6: [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    7: [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
}
HEX_REF = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
           (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]


class Msh:
    pass


def parse(path):
    """Parses an MSH 4.1 ASCII file; returns None (with a reason) for any other format."""
    with open(path, "rb") as f:
        raw = f.read()
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        return None, "binary file"
    lines = text.split("\n")
    i = 0
    m = Msh()
    m.names, m.entity_phys, m.nodes, m.blocks = {}, {}, {}, []
    m.n_elements = 0
    while i < len(lines):
        l = lines[i].strip()
        i += 1
        if l == "$MeshFormat":
            ver, ftype = lines[i].split()[:2]
            if ver != "4.1" or ftype != "0":
                return None, f"MSH {ver} {'binary' if ftype == '1' else 'ASCII'}"
            i += 1
        elif l == "$PhysicalNames":
            for _ in range(int(lines[i])):
                i += 1
                d, t, name = re.match(r'\s*(\d+)\s+(-?\d+)\s+"(.*)"', lines[i]).groups()
                m.names[(int(d), int(t))] = name
            i += 1
        elif l == "$Entities":
            counts = list(map(int, lines[i].split()))
            i += 1
            for dim, cnt in enumerate(counts):
                for _ in range(cnt):
                    v = lines[i].split()
                    i += 1
                    k = 4 if dim == 0 else 7
                    nphys = int(v[k])
                    m.entity_phys[(dim, int(v[0]))] = [int(x) for x in v[k + 1:k + 1 + nphys]]
        elif l == "$Nodes":
            nb = int(lines[i].split()[0])
            i += 1
            for _ in range(nb):
                dim, tag, par, n = map(int, lines[i].split())
                i += 1
                tags = [int(lines[i + k]) for k in range(n)]
                i += n
                for k in range(n):
                    x = lines[i + k].split()
                    m.nodes[tags[k]] = tuple(float(c) for c in x[:3])
                i += n
        elif l == "$Elements":
            nb, ne = map(int, lines[i].split()[:2])
            m.n_elements = ne
            i += 1
            for _ in range(nb):
                edim, etag, ty, n = map(int, lines[i].split())
                i += 1
                els = [list(map(int, lines[i + k].split())) for k in range(n)]
                i += n
                m.blocks.append((edim, etag, ty, els))
    return m, None


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def det3(c0, c1, c2):
    return dot(c0, cross(c1, c2))


G = 1 / 3 ** 0.5
HEX_GAUSS = [(G * a, G * b, G * c) for (a, b, c) in HEX_REF]


def hex_dets(p, points=HEX_REF + [(0, 0, 0)]):
    """det J of the trilinear map at `points` (by default the 8 corners and the centre)."""
    out = []
    for xi in points:
        cols = [[0.0, 0.0, 0.0] for _ in range(3)]
        for a, (ra, sa, ta) in enumerate(HEX_REF):
            g = (ra * (1 + sa * xi[1]) * (1 + ta * xi[2]) / 8,
                 sa * (1 + ra * xi[0]) * (1 + ta * xi[2]) / 8,
                 ta * (1 + ra * xi[0]) * (1 + sa * xi[1]) / 8)
            for d in range(3):
                for c in range(3):
                    cols[d][c] += p[a][c] * g[d]
        out.append(det3(*cols))
    return out


def prism_det(p, r, s, t):
    """det J of the prism's map at (r, s, t)."""
    tri = (1 - r - s, r, s)
    dtri = ((-1, -1), (1, 0), (0, 1))
    cols = [[0.0, 0.0, 0.0] for _ in range(3)]
    for a in range(3):
        for b, sg in ((a, -1), (a + 3, 1)):
            h = (1 + sg * t) / 2
            g = (dtri[a][0] * h, dtri[a][1] * h, sg * tri[a] / 2)
            for d in range(3):
                for c in range(3):
                    cols[d][c] += p[b][c] * g[d]
    return det3(*cols)


PYR_BASE = [(-1, -1), (1, -1), (1, 1), (-1, 1)]


def pyramid_det(p, u, v):
    """det J of the pyramid's map where (xi, eta)/(1 - zeta) = (u, v) (independent of zeta)."""
    cols = [[0.0, 0.0, 0.0] for _ in range(3)]
    for a, (ra, sa) in enumerate(PYR_BASE):
        g = (ra * (1 + sa * v) / 4, sa * (1 + ra * u) / 4, (ra * sa * u * v - 1) / 4)
        for d in range(3):
            for c in range(3):
                cols[d][c] += p[a][c] * g[d]
    for c in range(3):
        cols[2][c] += p[4][c]
    return det3(*cols)


def orientation(ty, p):
    """The smallest signed measure of the cell's orientation (must be > 0)."""
    if ty == 4:
        return det3(sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]))
    if ty == 5:
        return min(hex_dets(p))
    if ty == 6:
        return min(prism_det(p, r, s, t) for t in (-1, 1) for (r, s) in ((0, 0), (1, 0), (0, 1)))
    if ty == 7:
        return min(pyramid_det(p, u, v) for (u, v) in PYR_BASE + [(0, 0)])
    if ty in (2, 3):  # counter-clockwise in (x, y): every corner turns left
        n = len(p)
        return min(cross(sub(p[(k + 1) % n], p[k]), sub(p[(k + 2) % n], p[(k + 1) % n]))[2]
                   for k in range(n))
    return 1.0


def measure(ty, p):
    """The cell's volume (3D) or area (2D)."""
    if ty == 4:
        return det3(sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0])) / 6
    if ty == 5:
        return sum(hex_dets(p, HEX_GAUSS))
    if ty == 6:  # the triangle's 3-point rule times 2-point Gauss (exact: det J is quadratic)
        return sum(prism_det(p, r, s, t) / 6 for t in (-G, G)
                   for (r, s) in ((1 / 6, 1 / 6), (2 / 3, 1 / 6), (1 / 6, 2 / 3)))
    if ty == 7:  # 2 x 2 Gauss in (u, v) (det J is biquadratic) times the integral of (1 - w)^2, 1/3
        return sum(pyramid_det(p, u, v) / 3 for u in (-G, G) for v in (-G, G))
    if ty in (2, 3):
        n = len(p)
        return sum(p[k][0] * p[(k + 1) % n][1] - p[(k + 1) % n][0] * p[k][1] for k in range(n)) / 2
    return 0.0


def centroid(ps):
    return tuple(sum(q[c] for q in ps) / len(ps) for c in range(3))


def facet_normal(ps, top):
    """The normal of a facet given by its node order (in 2D the edge's right-hand normal)."""
    if top == 3:
        if len(ps) == 3:
            return cross(sub(ps[1], ps[0]), sub(ps[2], ps[0]))
        return cross(sub(ps[2], ps[0]), sub(ps[3], ps[1]))
    t = sub(ps[1], ps[0])
    return (t[1], -t[0], 0.0)


def check(path, same_xy):
    m, why = parse(path)
    name = os.path.basename(path)
    if m is None:
        print(f"{name}: skipped ({why}; this checker reads MSH 4.1 ASCII)")
        return True
    errors = []
    bad_types = {ty for (_, _, ty, _) in m.blocks if ty not in TYPES}
    if bad_types:
        errors.append(f"element types {sorted(bad_types)} are not first-order types hvi reads")
        return report(path, m, {}, errors, [])
    top = max(TYPES[ty][1] for (_, _, ty, _) in m.blocks)

    # groups: (dim, tag) -> list of (type, nodes)
    groups = {}
    for (edim, etag, ty, els) in m.blocks:
        for pt in m.entity_phys.get((edim, etag), []):
            groups.setdefault((edim, pt), []).extend((ty, e[1:]) for e in els)
    cells = [(ty, e[1:]) for (edim, _, ty, els) in m.blocks if edim == top for e in els]

    # orientation
    worst, n_bad, total = None, 0, 0.0
    for ty, nodes in cells:
        o = orientation(ty, [m.nodes[t] for t in nodes])
        total += measure(ty, [m.nodes[t] for t in nodes])
        worst = o if worst is None else min(worst, o)
        if o <= 0:
            n_bad += 1
    if n_bad:
        errors.append(f"{n_bad} of {len(cells)} cells have non-positive orientation")

    # faces of the body cells: sorted node tuple -> [count, cell centroid]
    faces = {}
    for ty, nodes in cells:
        c = centroid([m.nodes[t] for t in nodes])
        for f in FACES[ty]:
            key = tuple(sorted(nodes[k] for k in f))
            faces.setdefault(key, [0, c])[0] += 1
    boundary = {k for k, v in faces.items() if v[0] == 1}
    covered = set()
    info = []
    for (d, t), els in sorted(groups.items()):
        if d != top - 1:
            continue
        gname = m.names.get((d, t), "")
        n_out, n_not = 0, 0
        for ty, nodes in els:
            key = tuple(sorted(nodes))
            v = faces.get(key)
            if v is None or v[0] != 1:
                n_not += 1
                continue
            covered.add(key)
            ps = [m.nodes[q] for q in nodes]
            if dot(facet_normal(ps, top), sub(centroid(ps), v[1])) > 0:
                n_out += 1
        if n_not:
            errors.append(f"group {gname} ({d}, {t}): {n_not} of {len(els)} facets are not "
                          f"a face of exactly one cell")
        info.append(f"{gname}: {n_out}/{len(els)} facets with outward node-order normal")
    if boundary - covered:
        errors.append(f"{len(boundary - covered)} of {len(boundary)} boundary faces are in "
                      f"no physical group of dimension {top - 1}")

    omega = [k for k in groups if k[0] == top and m.names.get(k) == "Omega"]
    if len(omega) != 1:
        errors.append(f"no single physical group \"Omega\" of dimension {top}")
    elif len(groups[omega[0]]) != len(cells):
        errors.append(f"Omega has {len(groups[omega[0]])} of the {len(cells)} cells")
    used = {t for _, nodes in cells for t in nodes}
    if len(used) != len(m.nodes):
        errors.append(f"{len(m.nodes) - len(used)} nodes are in no body cell")

    # (x, y) of every z layer against a 2D mesh
    ref = same_xy.get(name)
    if ref is None:
        mm = re.match(r"slab_q1_h(\d+)_z\d+\.msh$", name)
        cand = os.path.join(os.path.dirname(path), f"rect_q1_h{mm.group(1)}.msh") if mm else None
        ref = cand if cand and os.path.exists(cand) else None
    if ref is not None and top == 3:
        r, why = parse(ref)
        xy = {(p[0], p[1]) for p in r.nodes.values()}
        zs = {}
        for p in m.nodes.values():
            zs.setdefault(p[2], set()).add((p[0], p[1]))
        bad = [z for z, s in zs.items() if s != xy]
        if bad:
            errors.append(f"{len(bad)} of {len(zs)} z layers differ in (x, y) from "
                          f"{os.path.basename(ref)}")
        else:
            info.append(f"all {len(zs)} z layers have exactly the {len(xy)} (x, y) nodes of "
                        f"{os.path.basename(ref)}")
    info.insert(0, f"all {len(cells)} cells positively oriented" if not n_bad else "orientation FAILED")
    info.insert(1, f"smallest orientation measure {worst:.3e} (tet: 6 vol; hex, prism, pyramid: min corner det J; "
                   f"2D: min corner cross product); total {'volume' if top == 3 else 'area'} {total:.6g}")
    return report(path, m, groups, errors, info)


def report(path, m, groups, errors, info):
    name, size = os.path.basename(path), os.path.getsize(path)
    kinds = {}
    for (_, _, ty, els) in m.blocks:
        k = TYPES[ty][0] if ty in TYPES else f"type {ty}"
        kinds[k] = kinds.get(k, 0) + len(els)
    print(f"{name}: {'OK' if not errors else 'FAILED'}  ({len(m.nodes)} nodes, {m.n_elements} "
          f"elements: {', '.join(f'{v} {k}' for k, v in kinds.items())}; {size} bytes)")
    for (d, t), els in sorted(groups.items()):
        print(f"    group dim {d} tag {t} {m.names.get((d, t), '')!r}: {len(els)} elements")
    for s in info:
        print(f"    {s}")
    for e in errors:
        print(f"    ERROR: {e}")
    return not errors


DIR = os.path.dirname(os.path.abspath(__file__))

if __name__ == "__main__":
    args, same_xy = [], {}
    it = iter(sys.argv[1:])
    for a in it:
        if a == "--same-xy":
            a3, a2 = next(it).split("=")
            same_xy[os.path.basename(a3)] = a2
        else:
            args.append(a)
    files = args or sorted(glob.glob(os.path.join(DIR, "*.msh")))
    ok = all([check(f, same_xy) for f in files])
    sys.exit(0 if ok else 1)
