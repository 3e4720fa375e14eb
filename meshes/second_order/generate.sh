#!/usr/bin/env bash
# Regenerates every .msh file in this folder (second-order gmsh meshes, MSH 4.1 ASCII) from
# ../ring.geo, ../rectangle.geo, ../pyramid.geo, ../../examples/gallery/hertz_3d/hertz_3d.geo and
# cylinder.geo here (needs gmsh: `pip install gmsh`,
# and python3 with the gmsh module for mixed_order.msh and the checks at the end).
# Run from anywhere: bash meshes/second_order/generate.sh
set -euo pipefail
cd "$(dirname "$0")"
command -v gmsh >/dev/null || { echo "gmsh not found: pip install gmsh" >&2; exit 1; }

# SecondOrderIncomplete=1: the serendipity elements (8-node quadrangles, 20-node hexahedra,
# 15-node prisms, 13-node pyramids) instead of the complete Lagrange ones (9, 27, 18, 14 nodes).
INCOMPLETE=(-setnumber Mesh.SecondOrderIncomplete 1)

m2() { # m2 GEO OUT ARGS...: mesh GEO in 2D with ARGS into OUT (MSH 4.1 ASCII)
    local geo=$1 out=$2; shift 2
    gmsh -2 "$geo" "$@" -format msh41 -o "$out" >/dev/null
    echo "wrote $out ($(wc -c <"$out") bytes)"
}
m3() { # m3 GEO OUT ARGS...: mesh GEO in 3D with ARGS into OUT (MSH 4.1 ASCII)
    local geo=$1 out=$2; shift 2
    gmsh -3 "$geo" "$@" -format msh41 -o "$out" >/dev/null
    echo "wrote $out ($(wc -c <"$out") bytes)"
}

# 1. The quarter ring 1 <= r <= 2 (../ring.geo): n cells across the wall, 2n along the arc.
#    P2 (6-node triangles), Q9 (9-node quadrangles), Q8 (8-node quadrangles); the midside nodes on
#    the arcs lie on the circles (gmsh puts high-order nodes on the geometry).
for n in 2 4 8 16; do
    m2 ../ring.geo "ring_p2_n$n.msh" -setnumber n "$n" -setnumber quads 0 -order 2
    m2 ../ring.geo "ring_q9_n$n.msh" -setnumber n "$n" -setnumber quads 1 -order 2
    m2 ../ring.geo "ring_q8_n$n.msh" -setnumber n "$n" -setnumber quads 1 -order 2 "${INCOMPLETE[@]}"
done
# First-order companions for n = 2 (n = 4, 8, 16 are ../ring_p1_n*.msh, ../ring_q1_n*.msh).
m2 ../ring.geo ring_p1_n2.msh -setnumber n 2 -setnumber quads 0
m2 ../ring.geo ring_q1_n2.msh -setnumber n 2 -setnumber quads 1

# 2. The quarter-cylinder slab (cylinder.geo): the ring extruded by 0.5 in z, max(1, n/2) layers.
#    For n = 8 gmsh prints 6 warnings "Converged at iter. 3 ... xyz error = 0.00031526 ... on
#    surface 17" (reparametrizing 6 first-order vertices on r = 2 while extruding): harmless, check.py
#    finds every node of Outer on r = 2 to 1e-15 and at its edge's midpoint to 3e-9.
for n in 2 4 8; do
    m3 cylinder.geo "cylinder_tet10_n$n.msh" -setnumber n "$n" -setnumber kind 0 -order 2
    m3 cylinder.geo "cylinder_hex27_n$n.msh" -setnumber n "$n" -setnumber kind 1 -order 2
    m3 cylinder.geo "cylinder_hex20_n$n.msh" -setnumber n "$n" -setnumber kind 1 -order 2 "${INCOMPLETE[@]}"
done
for n in 2 4; do
    m3 cylinder.geo "cylinder_prism18_n$n.msh" -setnumber n "$n" -setnumber kind 2 -order 2
    m3 cylinder.geo "cylinder_prism15_n$n.msh" -setnumber n "$n" -setnumber kind 2 -order 2 "${INCOMPLETE[@]}"
done

# 3. The paper's rectangle (0,2)x(0,1) (../rectangle.geo), h = 1/n: Q9 and P2.
for n in 4 8 16; do
    m2 ../rectangle.geo "rect_q9_h$n.msh" -setnumber n "$n" -setnumber quads 1 -order 2
done
for n in 4 8; do
    m2 ../rectangle.geo "rect_p2_h$n.msh" -setnumber n "$n" -setnumber quads 0 -order 2
done

# 4. Files a reader must refuse.
# 13-node (serendipity) and 14-node pyramids: ../pyramid.geo with n = 2 (2 x 2 x 2 hexahedra over
# tetrahedra, a pyramid on each of the 4 interface quadrangles).
m3 ../pyramid.geo pyramid13.msh -setnumber n 2 -order 2 "${INCOMPLETE[@]}"
m3 ../pyramid.geo pyramid14.msh -setnumber n 2 -order 2
# Mixed order: (0,2)x(0,1), the left square two 3-node triangles, the right square two 6-node
# triangles, in the same surface entity (gmsh does not mesh this: built with its Python API).
python3 - mixed_order.msh <<'PY'
import sys
import gmsh
gmsh.initialize()
gmsh.option.setNumber("General.Verbosity", 0)
gmsh.model.add("mixed_order")
for c in (1, 2, 3, 4):
    gmsh.model.addDiscreteEntity(1, c)
gmsh.model.addDiscreteEntity(2, 1, [1, 2, 3, 4])
xy = [(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1),             # 1-6 corners
      (1.5, 0), (2, 0.5), (1.5, 0.5), (1.5, 1), (1, 0.5)]          # 7-11 midside (right square)
gmsh.model.mesh.addNodes(2, 1, list(range(1, 12)), [v for x, y in xy for v in (x, y, 0.0)])
# surface: 3-node triangles (type 2) and 6-node triangles (type 9), counter-clockwise
gmsh.model.mesh.addElementsByType(1, 2, [1, 2], [1, 2, 5, 1, 5, 4])
gmsh.model.mesh.addElementsByType(1, 9, [3, 4], [2, 3, 6, 7, 8, 9, 2, 6, 5, 9, 10, 11])
# boundary: 2-node lines (type 1) on the left square, 3-node lines (type 8) on the right one
gmsh.model.mesh.addElementsByType(1, 1, [5], [1, 2])            # bottom, x < 1
gmsh.model.mesh.addElementsByType(1, 8, [6], [2, 3, 7])         # bottom, x > 1
gmsh.model.mesh.addElementsByType(2, 8, [7], [3, 6, 8])         # right x = 2
gmsh.model.mesh.addElementsByType(3, 8, [8], [6, 5, 10])        # top, x > 1
gmsh.model.mesh.addElementsByType(3, 1, [9], [5, 4])            # top, x < 1
gmsh.model.mesh.addElementsByType(4, 1, [10], [4, 1])           # left x = 0
gmsh.model.addPhysicalGroup(1, [4], 1, "Gamma1")
gmsh.model.addPhysicalGroup(1, [2, 3], 2, "Gamma2")
gmsh.model.addPhysicalGroup(1, [1], 3, "Gamma3")
gmsh.model.addPhysicalGroup(2, [1], 5, "Omega")
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.write(sys.argv[1])
gmsh.finalize()
PY
echo "wrote mixed_order.msh ($(wc -c <mixed_order.msh) bytes)"

# 5. The 3D Hertz contact quarter block (../../examples/gallery/hertz_3d/hertz_3d.geo), tet10:
#    hf = element size near the contact patch, a/7 = 0.014 and a/10 = 0.01 (a = 0.1, the contact
#    radius; the gallery's linear mesh uses a/14 = 0.007), hc at its default 0.3. gmsh prints 8
#    harmless warnings "Skipping unknown volume 10 in physical volume 8" (also for the linear mesh):
#    the .geo's v() from BooleanFragments lists surface tags too; Omega is volume 1 alone.
m3 ../../examples/gallery/hertz_3d/hertz_3d.geo hertz_3d_tet10_a7.msh -setnumber hf 0.014 -order 2
m3 ../../examples/gallery/hertz_3d/hertz_3d.geo hertz_3d_tet10_a10.msh -setnumber hf 0.01 -order 2

# Element types, groups, nodes on the circles, orientation: check.py (fails the script on an error).
python3 check.py
echo "total: $(du -sh . | cut -f1)"
