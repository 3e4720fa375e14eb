#!/usr/bin/env bash
# Regenerates every .msh file in this folder from rectangle.geo (needs gmsh: `pip install gmsh`,
# and python3 for the sparse-tag copy). Run from anywhere: bash meshes/generate.sh
set -euo pipefail
cd "$(dirname "$0")"
command -v gmsh >/dev/null || { echo "gmsh not found: pip install gmsh" >&2; exit 1; }

mesh() { # mesh OUT ARGS...: mesh rectangle.geo with -setnumber ARGS into OUT
    local out=$1; shift
    gmsh -2 rectangle.geo "$@" -o "$out" >/dev/null
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
