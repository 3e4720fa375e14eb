#!/usr/bin/env python3
"""The README picture of the relaxation example: the contact force P(t) of a run (the total force
of group Gamma3 on the pad, y component, from contact_forces.csv) divided by P(0), against the
relaxation function φ(t) = 0.3 + 0.4 e^{−t/0.1} + 0.3 e^{−t} of the scene's material (held
indentation and proportional relaxation: P(t) = P(0) φ(t), Lee & Radok). No dependencies.

    hvi solve examples/gallery/relaxation/relaxation.msh --scene examples/gallery/relaxation/relaxation.toml --out runs/relaxation
    python3 examples/gallery/relaxation/force_svg.py runs/relaxation/contact_forces.csv examples/figures/relaxation_force.svg
"""
import csv, math, sys

phi = lambda t: 0.3 + 0.4 * math.exp(-t / 0.1) + 0.3 * math.exp(-t)
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["group"] == "Gamma3" and r["component"] == "y"]
points = sorted((float(r["time"]), -float(r["force"])) for r in rows)
p0 = points[0][1]
t_end = points[-1][0]

W, H, L, B, T, RM = 640, 400, 70, 50, 40, 20
X = lambda t: L + (W - L - RM) * t / t_end
Y = lambda v: H - B - (H - B - T) * v / 1.05
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">Held indentation: the contact force relaxes (P(0) = {p0:.4e} per unit length)</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for i in range(4):
    t = t_end * i / 3
    out.append(f'<text x="{X(t)}" y="{H-B+18}" text-anchor="middle">{t:.1f}</text>')
for v in [0.0, 0.25, 0.5, 0.75, 1.0]:
    out.append(f'<text x="{L-6}" y="{Y(v)+4}" text-anchor="end">{v:.2f}</text>')
    out.append(f'<line x1="{L}" y1="{Y(v)}" x2="{W-RM}" y2="{Y(v)}" stroke="#dddddd"/>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">time t</text>')
out.append(f'<text x="16" y="{(T+H-B)/2}" transform="rotate(-90 16 {(T+H-B)/2})" text-anchor="middle">P(t) / P(0)</text>')
curve = " ".join(f"{X(t_end*s/400):.1f},{Y(phi(t_end*s/400)):.1f}" for s in range(401))
out.append(f'<polyline points="{curve}" fill="none" stroke="#1f77b4" stroke-width="2"/>')
out.append(f'<line x1="{L}" y1="{Y(0.3)}" x2="{W-RM}" y2="{Y(0.3)}" stroke="#1f77b4" stroke-dasharray="5,4"/>')
for t, p in points:
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(p/p0):.1f}" r="3" fill="#d62728"/>')
out.append(f'<line x1="{W-300}" y1="{T+15}" x2="{W-275}" y2="{T+15}" stroke="#1f77b4" stroke-width="2"/><text x="{W-268}" y="{T+19}">φ(t) = G(t)/G(0) (dashed: G∞/G(0))</text>')
out.append(f'<circle cx="{W-288}" cy="{T+35}" r="3" fill="#d62728"/><text x="{W-268}" y="{T+39}">hvi, total contact force</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
worst = max(abs(p / p0 - phi(t)) for t, p in points)
print(f"wrote {sys.argv[2]}: P(0) = {p0:.6e}, max |P/P(0) − φ| = {worst:.2e}")
