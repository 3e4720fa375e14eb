#!/usr/bin/env python3
"""The gallery picture of the asphalt's creep under a sphere, on a logarithmic time axis: the
contact radius a(t) of a run (from gamma3.csv: the edge of the gap's (r − a)^{3/2} opening fitted
through the first two free nodes, as for the gel) against Lee & Radok's a(t)³ = (3PR/4)(1 − ν²) D(t),
D the creep compliance of the scene's relaxation modulus E(t) (Gibson et al. 2003, the scene names
the source), found by the roots of its Carson transform. No dependencies.

    hvi solve examples/gallery/gel/gel.msh --scene examples/gallery/asphalt/asphalt.toml --out runs/asphalt
    python3 examples/gallery/asphalt/creep_svg.py runs/asphalt/gamma3.csv examples/figures/asphalt_creep.svg
"""
import csv, math, sys
from collections import defaultdict

TERMS = [(1.430e1, 1.500e7), (3.210e1, 8.005e5), (7.420e1, 4.272e4), (1.796e2, 2.280e3),
         (4.588e2, 1.217e2), (1.232e3, 6.493e0), (2.956e3, 3.465e-1), (5.286e3, 1.849e-2),
         (6.531e3, 9.869e-4), (5.727e3, 5.267e-5), (3.848e3, 2.811e-6), (2.160e3, 1.500e-7)]
E_INF, NU, R = 412.8, 0.35, 1.0
P = 0.136718  # the scene's force (examples/gallery/asphalt/asphalt.toml)


def compliance_terms():
    """(1/(s_j F'(s_j)), s_j) over the roots s_j < 0 of F(s) = E∞ + Σ E_i s/(s + 1/ρ_i)."""
    f = lambda s: E_INF + sum(e * s / (s + 1 / rho) for e, rho in TERMS)
    df = lambda s: sum(e / rho / (s + 1 / rho) ** 2 for e, rho in TERMS)
    poles = sorted(1 / rho for _, rho in TERMS)
    out = []
    for i in range(len(poles)):
        a = math.log(poles[0] * 1e-30) if i == 0 else math.log(poles[i - 1])
        b = math.log(poles[i])
        for _ in range(200):
            mid = 0.5 * (a + b)
            if f(-math.exp(mid)) > 0:
                a = mid
            else:
                b = mid
        s = -math.exp(0.5 * (a + b))
        out.append((1 / (s * df(s)), s))
    return out


TERMS_D = compliance_terms()
D = lambda t: 1 / E_INF + sum(c * math.exp(s * t) for c, s in TERMS_D)
lee_radok = lambda t: (0.75 * P * R * (1 - NU * NU) * D(t)) ** (1 / 3)

rows = defaultdict(list)
for r in csv.DictReader(open(sys.argv[1])):
    gap = R - math.sqrt(R * R - float(r["x"]) ** 2) - float(r["u_nu"])
    rows[float(r["time"])].append((float(r["x"]), int(float(r["status"])) == 2, gap))
points = []
for t, nodes in sorted(rows.items()):
    if t <= 0:
        continue
    nodes.sort()
    last = max(i for i, n in enumerate(nodes) if n[1])
    (r1, _, g1), (r2, _, g2) = nodes[last + 1], nodes[last + 2]
    q = (g1 / g2) ** (2 / 3)
    points.append((t, (r1 - q * r2) / (1 - q)))
lo, hi = math.floor(math.log10(points[0][0])), math.ceil(math.log10(points[-1][0]))
top = 1.1 * max(max(a for _, a in points), lee_radok(10 ** hi))

W, H, L, B, T, RM = 640, 400, 80, 50, 40, 20
X = lambda t: L + (W - L - RM) * (math.log10(t) - lo) / (hi - lo)
Y = lambda a: H - B - (H - B - T) * a / top
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">Asphalt concrete under a sphere, a microsecond to a year</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for d in range(lo, hi + 1):
    out.append(f'<line x1="{X(10**d):.1f}" y1="{T}" x2="{X(10**d):.1f}" y2="{H-B}" stroke="#eeeeee"/>')
    if (d - lo) % 2 == 0:
        out.append(f'<text x="{X(10**d):.1f}" y="{H-B+18}" text-anchor="middle">1e{d}</text>')
for i in range(7):
    a = 0.01 * i
    if a <= top:
        out.append(f'<text x="{L-6}" y="{Y(a)+4}" text-anchor="end">{a:.2f}</text>')
        out.append(f'<line x1="{L}" y1="{Y(a)}" x2="{W-RM}" y2="{Y(a)}" stroke="#dddddd"/>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">time t [s] (logarithmic; relaxation times 1.5e-7 … 1.5e7 s)</text>')
out.append(f'<text x="18" y="{(T+H-B)/2}" transform="rotate(-90 18 {(T+H-B)/2})" text-anchor="middle">contact radius a(t) / R</text>')
n = 600
curve = " ".join(f"{X(10 ** (lo + (hi - lo) * s / n)):.1f},{Y(lee_radok(10 ** (lo + (hi - lo) * s / n))):.1f}"
                 for s in range(n + 1))
out.append(f'<polyline points="{curve}" fill="none" stroke="#1f77b4" stroke-width="2"/>')
for t, a in points:
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(a):.1f}" r="3" fill="#d62728"/>')
out.append(f'<line x1="{L+20}" y1="{T+20}" x2="{L+45}" y2="{T+20}" stroke="#1f77b4" stroke-width="2"/><text x="{L+52}" y="{T+24}">Lee &amp; Radok: a³ = (3PR/4)(1 − ν²) D(t)</text>')
out.append(f'<circle cx="{L+32}" cy="{T+40}" r="3" fill="#d62728"/><text x="{L+52}" y="{T+44}">hvi, axisymmetric, 252 steps, one factorisation</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
worst = max(abs(a / lee_radok(t) - 1) for t, a in points)
print(f"wrote {sys.argv[2]}: a({points[0][0]:g}) = {points[0][1]:.5f}, a({points[-1][0]:g}) = {points[-1][1]:.5f}, "
      f"max |a/a_LR − 1| = {100*worst:.2f} % over {len(points)} frames")
