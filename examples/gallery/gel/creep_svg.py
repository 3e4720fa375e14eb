#!/usr/bin/env python3
"""The gallery picture of the gel's creep: the contact radius a(t) of a run under the constant
force P (from gamma3.csv: the edge of the gap's (r − a)^{3/2} opening fitted through the first two
free nodes, as tests/creep_indentation.rs measures it) against Lee & Radok's a(t)³ = (3PR/4) C(t),
C the creep function of (1 − ν²)/E for the scene's material (G(t) = 0.01 + 0.99 e^{−t}, K = 10;
docs/method.md §8.6). No dependencies.

    hvi solve examples/gallery/gel/gel.msh --scene examples/gallery/gel/gel.toml --out runs/gel
    python3 examples/gallery/gel/creep_svg.py runs/gel/gamma3.csv examples/figures/gel_creep.svg
"""
import csv, math, sys
from collections import defaultdict

K, G0, GI, TAU, P, R = 10.0, 1.0, 0.01, 1.0, 1.5e-5, 1.0


def creep(t):
    """C(t): the sum of the residues of (3K D + 4N) D / (s 4N (3K D + N)) e^{st}."""
    poles = [0.0, -GI / (TAU * G0), -(3 * K + GI) / (TAU * (3 * K + G0))]
    num = lambda s: (3 * K * (s + 1 / TAU) + 4 * (G0 * s + GI / TAU)) * (s + 1 / TAU)
    total = 0.0
    for i, si in enumerate(poles):
        d = 4 * G0 * (3 * K + G0)
        for j, sj in enumerate(poles):
            if j != i:
                d *= si - sj
        total += num(si) * math.exp(si * t) / d
    return total


lee_radok = lambda t: (0.75 * P * R * creep(t)) ** (1 / 3)

rows = defaultdict(list)
for r in csv.DictReader(open(sys.argv[1])):
    gap = R - math.sqrt(R * R - float(r["x"]) ** 2) - float(r["u_nu"])
    rows[float(r["time"])].append((float(r["x"]), int(float(r["status"])) == 2, gap))
points = []
for t, nodes in sorted(rows.items()):
    nodes.sort()
    last = max(i for i, n in enumerate(nodes) if n[1])
    (r1, _, g1), (r2, _, g2) = nodes[last + 1], nodes[last + 2]
    q = (g1 / g2) ** (2 / 3)
    points.append((t, (r1 - q * r2) / (1 - q)))
t_end = points[-1][0]
top = 1.1 * max(lee_radok(t_end), points[-1][1])
# a logarithmic time axis (the steps grow with time, docs/method.md §20): t = 0 left out
points = [(t, a) for t, a in points if t > 0]
lo, hi = math.floor(math.log10(points[0][0])), math.ceil(math.log10(t_end))

W, H, L, B, T, RM = 640, 400, 80, 50, 40, 20
X = lambda t: L + (W - L - RM) * (math.log10(t) - lo) / (hi - lo)
Y = lambda a: H - B - (H - B - T) * a / top
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">A relaxing gel under a sphere and a constant force: the contact creeps</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for d in range(lo, hi + 1):
    out.append(f'<line x1="{X(10**d):.1f}" y1="{T}" x2="{X(10**d):.1f}" y2="{H-B}" stroke="#eeeeee"/>')
    out.append(f'<text x="{X(10**d):.1f}" y="{H-B+18}" text-anchor="middle">1e{d}</text>')
for i in range(6):
    a = 0.07 * i / 5
    if a <= top:
        out.append(f'<text x="{L-6}" y="{Y(a)+4}" text-anchor="end">{a:.3f}</text>')
        out.append(f'<line x1="{L}" y1="{Y(a)}" x2="{W-RM}" y2="{Y(a)}" stroke="#dddddd"/>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">time t, logarithmic (the shear relaxes with τ = 1, the creep with τ G₀/G∞ = 100)</text>')
out.append(f'<text x="18" y="{(T+H-B)/2}" transform="rotate(-90 18 {(T+H-B)/2})" text-anchor="middle">contact radius a(t)</text>')
n = 600
curve = " ".join(f"{X(10 ** (lo + (hi - lo) * s / n)):.1f},{Y(lee_radok(10 ** (lo + (hi - lo) * s / n))):.1f}"
                 for s in range(n + 1))
out.append(f'<polyline points="{curve}" fill="none" stroke="#1f77b4" stroke-width="2"/>')
for t, a in points:
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(a):.1f}" r="3" fill="#d62728"/>')
out.append(f'<line x1="{L+20}" y1="{T+20}" x2="{L+45}" y2="{T+20}" stroke="#1f77b4" stroke-width="2"/><text x="{L+52}" y="{T+24}">Lee &amp; Radok: a³ = (3PR/4) C(t)</text>')
out.append(f'<circle cx="{L+32}" cy="{T+40}" r="3" fill="#d62728"/><text x="{L+52}" y="{T+44}">hvi, axisymmetric, mean dilatation, 95 growing steps</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
worst = max(abs(a / lee_radok(t) - 1) for t, a in points)
print(f"wrote {sys.argv[2]}: a(0) = {points[0][1]:.5f}, a({t_end:g}) = {points[-1][1]:.5f}, "
      f"max |a/a_LR − 1| = {100*worst:.2f} % over {len(points)} output steps")
