#!/usr/bin/env python3
"""The README picture of the 2D Hertz example: the nodal contact pressure of a run against
Hertz's p(x) = p0 sqrt(1 - x²/a²), a² = 4PR/(πE*), p0 = 2P/(πa), P twice the half's contact force.
No dependencies (writes the SVG by hand).

    hvi solve examples/gallery/hertz_2d/hertz_2d_h3.msh --scene examples/gallery/hertz_2d/hertz_2d.toml --out runs/hertz_2d
    python3 examples/gallery/hertz_2d/pressure_svg.py runs/hertz_2d/gamma3.csv examples/figures/hertz_2d_pressure.svg
"""
import csv, math, sys

E, NU, R = 1.0, 0.3, 1.0
rows = list(csv.DictReader(open(sys.argv[1])))
t_end = max(float(r["time"]) for r in rows)
rows = [r for r in rows if float(r["time"]) == t_end]
P = 2 * sum(float(r["force"]) for r in rows)
e_star = E / (1 - NU * NU)
a = math.sqrt(4 * P * R / (math.pi * e_star))
p0 = 2 * P / (math.pi * a)
nodes = sorted((float(r["x"]), float(r["pressure"])) for r in rows if float(r["x"]) <= 1.5 * a)

W, H, L, B, T, RM = 640, 400, 70, 50, 40, 20
xmax, pmax = 1.5 * a, 1.1 * p0
X = lambda x: L + (W - L - RM) * x / xmax
Y = lambda p: H - B - (H - B - T) * p / pmax
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">2D Hertz: contact pressure on the block (P = {P:.4e} per unit length)</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for i in range(4):
    x = xmax * i / 3
    out.append(f'<text x="{X(x)}" y="{H-B+18}" text-anchor="middle">{x:.3f}</text>')
    p = pmax * i / 3
    out.append(f'<text x="{L-6}" y="{Y(p)+4}" text-anchor="end">{p:.3f}</text>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">x</text>')
out.append(f'<text x="16" y="{(T+H-B)/2}" transform="rotate(-90 16 {(T+H-B)/2})" text-anchor="middle">pressure</text>')
curve = " ".join(f"{X(a*s/200):.1f},{Y(p0*math.sqrt(max(0.0, 1-(s/200)**2))):.1f}" for s in range(201))
out.append(f'<polyline points="{curve} {X(xmax):.1f},{Y(0):.1f}" fill="none" stroke="#1f77b4" stroke-width="2"/>')
for x, p in nodes:
    out.append(f'<circle cx="{X(x):.1f}" cy="{Y(p):.1f}" r="3" fill="#d62728"/>')
out.append(f'<line x1="{W-250}" y1="{T+15}" x2="{W-225}" y2="{T+15}" stroke="#1f77b4" stroke-width="2"/><text x="{W-218}" y="{T+19}">Hertz, a = {a:.4f}, p₀ = {p0:.4f}</text>')
out.append(f'<circle cx="{W-238}" cy="{T+35}" r="3" fill="#d62728"/><text x="{W-218}" y="{T+39}">hvi, nodal pressure</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
print(f"wrote {sys.argv[2]}: P = {P:.6e}, a = {a:.5f}, p0 = {p0:.5f}")
