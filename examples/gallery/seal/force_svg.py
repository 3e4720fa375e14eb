#!/usr/bin/env python3
"""The gallery picture of the seal example: the sealing force F(t) of a run (the total force of
group Gamma3 on the seal, y component, from contact_forces.csv; the whole ring's, N) against time,
with the long-term elastic force F∞ (the same mesh with the elastomer's long-term moduli
G∞ = 0.1 MPa, κ = 100 MPa: 12.624 N, tests/gallery_seal.rs) and one exponential
F∞ + (F(t_r) − F∞) e^{−(t − t_r)/τ} from the end of the push t_r = 5 s, τ = 10 s. No dependencies.

    hvi solve examples/gallery/seal/seal.msh --scene examples/gallery/seal/seal.toml --out runs/seal
    python3 examples/gallery/seal/force_svg.py runs/seal/contact_forces.csv examples/figures/seal_force.svg
"""
import csv, math, sys

F_LONG, T_R, TAU = 12.624, 5.0, 10.0
rows = [r for r in csv.DictReader(open(sys.argv[1])) if r["group"] == "Gamma3" and r["component"] == "y"]
points = sorted((float(r["time"]), float(r["force"])) for r in rows)
t_end = points[-1][0]
f_r = min(points, key=lambda p: abs(p[0] - T_R))[1]
f_top = max(f for _, f in points) * 1.1

W, H, L, B, T, RM = 640, 400, 70, 50, 40, 20
X = lambda t: L + (W - L - RM) * t / t_end
Y = lambda v: H - B - (H - B - T) * v / f_top
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">Rubber seal pushed by 0.2 mm over 5 s, then held: the sealing force relaxes</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for i in range(5):
    t = t_end * i / 4
    out.append(f'<text x="{X(t)}" y="{H-B+18}" text-anchor="middle">{t:.0f}</text>')
step = 20 if f_top > 60 else 5
for v in range(0, int(f_top) + 1, step):
    out.append(f'<text x="{L-6}" y="{Y(v)+4}" text-anchor="end">{v}</text>')
    out.append(f'<line x1="{L}" y1="{Y(v)}" x2="{W-RM}" y2="{Y(v)}" stroke="#dddddd"/>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">time t [s]</text>')
out.append(f'<text x="16" y="{(T+H-B)/2}" transform="rotate(-90 16 {(T+H-B)/2})" text-anchor="middle">sealing force F [N]</text>')
curve = " ".join(f"{X(t):.1f},{Y(F_LONG + (f_r - F_LONG) * math.exp(-(t - T_R) / TAU)):.1f}"
                 for t in [T_R + (t_end - T_R) * s / 400 for s in range(401)])
out.append(f'<polyline points="{curve}" fill="none" stroke="#1f77b4" stroke-width="2"/>')
out.append(f'<line x1="{L}" y1="{Y(F_LONG)}" x2="{W-RM}" y2="{Y(F_LONG)}" stroke="#1f77b4" stroke-dasharray="5,4"/>')
for t, f in points:
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(f):.1f}" r="3" fill="#d62728"/>')
out.append(f'<line x1="{W-330}" y1="{T+15}" x2="{W-305}" y2="{T+15}" stroke="#1f77b4" stroke-width="2"/><text x="{W-298}" y="{T+19}">F∞ + (F(5) − F∞) e^(−(t−5)/τ), τ = 10 s</text>')
out.append(f'<line x1="{W-330}" y1="{T+35}" x2="{W-305}" y2="{T+35}" stroke="#1f77b4" stroke-dasharray="5,4"/><text x="{W-298}" y="{T+39}">F∞ = {F_LONG} N: elastic, long-term moduli</text>')
out.append(f'<circle cx="{W-318}" cy="{T+55}" r="3" fill="#d62728"/><text x="{W-298}" y="{T+59}">hvi, total contact force</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
print(f"wrote {sys.argv[2]}: F({T_R:g}) = {f_r:.4f} N, F({t_end:g}) = {points[-1][1]:.4f} N, F∞ = {F_LONG} N")
