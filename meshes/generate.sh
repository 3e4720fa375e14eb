#!/usr/bin/env bash
# Regenerates every .msh file in this folder from rectangle.geo, slab.geo, block.geo and bracket.geo
# (needs gmsh: `pip install gmsh`, and python3 for the sparse-tag copy and check_orientation.py).
# Run from anywhere: bash meshes/generate.sh
set -euo pipefail
cd "$(dirname "$0")"
command -v gmsh >/dev/null || { echo "gmsh not found: pip install gmsh" >&2; exit 1; }

mesh() { # mesh OUT ARGS...: mesh rectangle.geo with -setnumber ARGS into OUT
    local out=$1; shift
    gmsh -2 rectangle.geo "$@" -o "$out" >/dev/null
    echo "wrote $out ($(wc -c <"$out") bytes)"
}
mesh3() { # mesh3 GEO OUT ARGS...: mesh GEO in 3D with -setnumber ARGS into OUT (MSH 4.1 ASCII)
    local geo=$1 out=$2; shift 2
    gmsh -3 "$geo" "$@" -format msh41 -o "$out" >/dev/null
    echo "wrote $out ($(wc -c <"$out") bytes)"
}

# Q1, square h x h cells, MSH 4.1 ASCII: the convergence study meshes.
for n in 8 16 32 64; do
    mesh "rect_q1_h$n.msh" -setnumber n "$n" -setnumber quads 1 -format msh41
done
# P1 (each square split into two triangles), h = 1/16.
mesh rect_p1_h16.msh -setnumber n 16 -setnumber quads 0 -format msh41
# The same Q1 h = 1/16 mesh in MSH 4.1 binary and in MSH 2.2 ASCII.
mesh rect_q1_h16_bin.msh -setnumber n 16 -setnumber quads 1 -format msh41 -bin
mesh rect_q1_h16_v22.msh -setnumber n 16 -setnumber quads 1 -format msh22
# Q1 with wide 2h x h cells (1/h parts along each side), h = 1/16.
mesh rect_q1_h16_wide.msh -setnumber n 16 -setnumber quads 1 -setnumber wide 1 -format msh41
# Mixed: quadrangles on x < 1, triangles on x > 1, h = 1/4.
mesh rect_mixed_h4.msh -setnumber n 4 -setnumber mixed 1 -format msh41
# Two halves x < 1 and x > 1, each its own physical group (Left 6, Right 7): two materials.
mesh rect_halves_q1_h4.msh -setnumber n 4 -setnumber halves 1 -setnumber quads 1 -format msh41
mesh rect_halves_p1_h4.msh -setnumber n 4 -setnumber halves 1 -setnumber quads 0 -format msh41
# Only the groups the paper names (Gamma1, Gamma2, Gamma3, Omega; no Gamma2_top).
mesh rect_q1_h16_plain.msh -setnumber n 16 -setnumber quads 1 -setnumber plain 1 -format msh41
mesh rect_p1_h8_plain.msh -setnumber n 8 -setnumber quads 0 -setnumber plain 1 -format msh41

# Sparse node tags: a copy of rect_q1_h8.msh post-processed (by the python below, not by gmsh):
# node tag t becomes 10 t + 3 (gaps, not starting at 1), element tag t becomes t + 1000, and the
# nodes of every node block are listed in reverse order. Ascending tag order is unchanged, so it
# reads into exactly the same mesh as rect_q1_h8.msh.
python3 - rect_q1_h8.msh rect_q1_h8_sparse.msh <<'PY'
import sys
src, dst = sys.argv[1], sys.argv[2]
lines = open(src).read().split("\n")
out, i = [], 0
node = lambda t: 10 * t + 3
while i < len(lines):
    l = lines[i]
    out.append(l); i += 1
    if l == "$Nodes":
        nb, nn, lo, hi = map(int, lines[i].split()); i += 1
        out.append(f"{nb} {nn} {node(lo)} {node(hi)}")
        for _ in range(nb):
            dim, tag, par, n = map(int, lines[i].split()); i += 1
            out.append(f"{dim} {tag} {par} {n}")
            tags = [int(lines[i + k]) for k in range(n)]; i += n
            xyz = lines[i:i + n]; i += n
            out += [str(node(t)) for t in reversed(tags)] + list(reversed(xyz))
    elif l == "$Elements":
        nb, ne, lo, hi = map(int, lines[i].split()); i += 1
        out.append(f"{nb} {ne} {lo + 1000} {hi + 1000}")
        for _ in range(nb):
            hdr = lines[i]; i += 1
            out.append(hdr)
            for _ in range(int(hdr.split()[3])):
                v = list(map(int, lines[i].split())); i += 1
                out.append(" ".join([str(v[0] + 1000)] + [str(node(t)) for t in v[1:]]) + " ")
open(dst, "w").write("\n".join(out))
PY
echo "wrote rect_q1_h8_sparse.msh ($(wc -c <rect_q1_h8_sparse.msh) bytes)"

# 3D. The slab (0,2)x(0,1)x(0,Lz): rectangle.geo's grid extruded in cubic h x h x h cells.
mesh3 slab.geo slab_q1_h8_z1.msh -setnumber n 8 -setnumber layers 1
mesh3 slab.geo slab_q1_h8_z3.msh -setnumber n 8 -setnumber layers 3
mesh3 slab.geo slab_q1_h16_z4.msh -setnumber n 16 -setnumber layers 4
mesh3 slab.geo slab_p1_h4.msh -setnumber n 4 -setnumber layers 2 -setnumber hexes 0
# The indentation block (0,1)x(0,1)x(0,0.5): unstructured tetrahedra and 8 x 8 x 4 hexahedra.
mesh3 block.geo block_p1.msh -setnumber hexes 0 -setnumber lc 0.08
mesh3 block.geo block_q1_h8.msh -setnumber hexes 1 -setnumber n 8
# Coarse tetrahedra of the block (lc 0.25: 91 nodes, 222 tetrahedra) in MSH 4.1 binary and MSH 2.2
# ASCII, the other two formats' bases of the 3D mutation campaign (tests/mesh_mutations_3d.rs).
mesh3 block.geo block_p1_bin.msh -setnumber hexes 0 -setnumber lc 0.25 -bin
gmsh -3 block.geo -setnumber hexes 0 -setnumber lc 0.25 -format msh22 -o block_p1_v22.msh >/dev/null
echo "wrote block_p1_v22.msh ($(wc -c <block_p1_v22.msh) bytes)"
# Prisms (an extruded triangulation, Layers + Recombine) under tetrahedra on the same interface.
gmsh -3 prism.geo -format msh41 -o prism_tet.msh >/dev/null
echo "wrote prism_tet.msh"
# Hexahedra over tetrahedra: gmsh puts a pyramid on every interface quadrangle by itself.
mesh3 pyramid.geo pyramid_hex_tet.msh
# The L bracket (OpenCASCADE), tetrahedra.
mesh3 bracket.geo bracket_p1.msh -setnumber lc 0.03

# The quarter ring 1 <= r <= 2 (Lamé under internal pressure: tests/pressure.rs, examples/ring.toml):
# nested structured grids, n cells across the wall, Q1 and P1.
for n in 4 8 16; do
    gmsh -2 ring.geo -setnumber n "$n" -setnumber quads 1 -format msh41 -o "ring_q1_n$n.msh" >/dev/null
    gmsh -2 ring.geo -setnumber n "$n" -setnumber quads 0 -format msh41 -o "ring_p1_n$n.msh" >/dev/null
    echo "wrote ring_q1_n$n.msh, ring_p1_n$n.msh"
done
# the reference of the curved-domain study (examples/gallery/ring/ring_study.toml)
gmsh -2 ring.geo -setnumber n 32 -setnumber quads 1 -format msh41 -o ring_q1_n32.msh >/dev/null
echo "wrote ring_q1_n32.msh"

# Cook's membrane (tests/cook.rs, docs/method.md §8.4): nested structured grids, n cells per edge,
# Q1 and P1, in the subfolder cook/ (then checked like the files here).
mkdir -p cook
for n in 4 8 16 32 64; do
    gmsh -2 cook.geo -setnumber n "$n" -setnumber quads 1 -format msh41 -o "cook/cook_q1_n$n.msh" >/dev/null
    gmsh -2 cook.geo -setnumber n "$n" -setnumber quads 0 -format msh41 -o "cook/cook_p1_n$n.msh" >/dev/null
    echo "wrote cook/cook_q1_n$n.msh, cook/cook_p1_n$n.msh"
done
python3 check_orientation.py cook/*.msh | grep -E '^[^ ]|ERROR'

# Two bodies of one mesh touching at a point (tests/two_body_hertz.rs, docs/method.md §18), in the
# subfolder two_bodies/ (then checked like the files here): two cylinders R1 = 1 and R2 = 2 (2D,
# quarter disks, P1 triangles of 0.002 = a/25 near the contact) and two spheres R1 = R2 = 2 (3D,
# quarters of hemispheres, tetrahedra of 0.01 = a/10 near the contact). Their second-order meshes
# (docs/method.md §18.6): the cylinders in 6-node triangles of a/8 and a/16, the spheres in 10-node
# tetrahedra of a/7 and a/10, and the gallery's punch on its pad (../examples/gallery/two_bodies)
# in 6-node triangles and 9-node quadrangles (tests/petsc.rs). check_orientation.py reads
# first-order files only.
(
    cd two_bodies
    gmsh -2 cylinders.geo -format msh41 -o cylinders_p1.msh >/dev/null
    echo "wrote two_bodies/cylinders_p1.msh ($(wc -c <cylinders_p1.msh) bytes)"
    gmsh -3 spheres.geo -format msh41 -o spheres_p1.msh >/dev/null
    echo "wrote two_bodies/spheres_p1.msh ($(wc -c <spheres_p1.msh) bytes)"
    for a in 8 16; do
        gmsh -2 cylinders.geo -setnumber hf "$(python3 -c "print(0.05 / $a)")" -order 2 -format msh41 \
            -o "cylinders_p2_a$a.msh" >/dev/null
        echo "wrote two_bodies/cylinders_p2_a$a.msh ($(wc -c <"cylinders_p2_a$a.msh") bytes)"
    done
    gmsh -3 spheres.geo -setnumber hf 0.0143 -order 2 -format msh41 -o spheres_tet10_a7.msh >/dev/null
    gmsh -3 spheres.geo -setnumber hf 0.01 -order 2 -format msh41 -o spheres_tet10_a10.msh >/dev/null
    gmsh -2 ../../examples/gallery/two_bodies/two_bodies.geo -order 2 -format msh41 -o gallery_o2.msh >/dev/null
    echo "wrote two_bodies/spheres_tet10_a7.msh, spheres_tet10_a10.msh, gallery_o2.msh"
)
python3 check_orientation.py two_bodies/*_p1.msh | grep -E '^[^ ]|ERROR'

# Orientation, boundary groups and the slabs' (x, y) grids of every MSH 4.1 ASCII file here: one
# line per file (OK or FAILED) and any ERROR lines; fails the script if any check fails.
python3 check_orientation.py | grep -E '^[^ ]|ERROR'

# The gallery's Hertz meshes (examples/gallery/hertz_2d, hertz_3d; README "Problems you can pose"):
# 2D with element size hf = 0.005, 0.0025, 0.00125 on the contact, 3D with its default hf.
(
    cd ../examples/gallery/hertz_2d
    for k in 1 2 3; do
        hf=$(python3 -c "print(0.005 / 2 ** ($k - 1))")
        gmsh -2 hertz_2d.geo -setnumber hf "$hf" -format msh41 -o "hertz_2d_h$k.msh" >/dev/null
        echo "wrote hertz_2d_h$k.msh ($(wc -c <"hertz_2d_h$k.msh") bytes)"
    done
    cd ../hertz_3d
    gmsh -3 hertz_3d.geo -format msh41 -o hertz_3d.msh >/dev/null
    echo "wrote hertz_3d.msh ($(wc -c <hertz_3d.msh) bytes)"
)

# The gallery's Cattaneo–Mindlin meshes (examples/gallery/cattaneo_2d, cattaneo_3d; tests/friction.rs).
(
    cd ../examples/gallery/cattaneo_2d
    gmsh -2 cattaneo_2d.geo -format msh41 -o cattaneo_2d.msh >/dev/null
    echo "wrote cattaneo_2d.msh ($(wc -c <cattaneo_2d.msh) bytes)"
    cd ../cattaneo_3d
    gmsh -3 cattaneo_3d.geo -format msh41 -o cattaneo_3d.msh >/dev/null
    echo "wrote cattaneo_3d.msh ($(wc -c <cattaneo_3d.msh) bytes)"
    gmsh -3 cattaneo_3d.geo -setnumber hf 0.009 -format msh41 -o cattaneo_3d_coarse.msh >/dev/null
    echo "wrote cattaneo_3d_coarse.msh ($(wc -c <cattaneo_3d_coarse.msh) bytes)"
)

# The gallery's two contact zones (examples/gallery/two_zones): Q1, h = 0.05, 0.02 at the right foot.
(
    cd ../examples/gallery/two_zones
    gmsh -2 two_zones.geo -format msh41 -o two_zones.msh >/dev/null
    echo "wrote two_zones.msh ($(wc -c <two_zones.msh) bytes)"
)
