#!/usr/bin/env python3
"""The gallery picture of the two-body example: the forces between the punch and the pad against
time, from a run's contact_forces.csv (the rows of the slave group PunchNose: the force the pad
exerts on the punch; the pad's top is flat, so its y component is the normal force N and its x
component the friction force T). With μN, and the normal force of the same scene with the pad
elastic at its instantaneous moduli G(0) = 1.2, κ = 4 (F₀) and at its long-term ones G∞ = 0.2
(F∞), both measured by tests/gallery_two_bodies.rs. No dependencies.

    hvi solve examples/gallery/two_bodies/two_bodies.msh --scene examples/gallery/two_bodies/two_bodies.toml --out runs/two_bodies
    python3 examples/gallery/two_bodies/force_svg.py runs/two_bodies/contact_forces.csv examples/figures/two_bodies_force.svg
"""
import csv, sys

MU, F_0, F_INF, T_PRESS, T_SLIDE = 0.4, 0.072006, 0.017462, 0.2, 4.0
forces = {}
for r in csv.DictReader(open(sys.argv[1])):
    if r["group"] == "PunchNose":
        forces.setdefault(float(r["time"]), {})[r["component"]] = float(r["force"])
times = sorted(forces)
normal = [forces[t]["y"] for t in times]
friction = [-forces[t]["x"] for t in times]
t_end, f_top = times[-1], 0.09

W, H, L, B, T, RM = 640, 400, 70, 50, 40, 20
X = lambda t: L + (W - L - RM) * t / t_end
Y = lambda v: H - B - (H - B - T) * v / f_top
out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="13">',
       f'<rect width="{W}" height="{H}" fill="white"/>',
       f'<text x="{W/2}" y="22" text-anchor="middle" font-size="15">Punch on a relaxing pad: pressed, held, slid with μ = {MU}</text>',
       f'<line x1="{L}" y1="{H-B}" x2="{W-RM}" y2="{H-B}" stroke="black"/><line x1="{L}" y1="{H-B}" x2="{L}" y2="{T}" stroke="black"/>']
for i in range(6):
    t = t_end * i / 5
    out.append(f'<text x="{X(t)}" y="{H-B+18}" text-anchor="middle">{t:g}</text>')
for i in range(5):
    v = 0.02 * i
    out.append(f'<text x="{L-6}" y="{Y(v)+4}" text-anchor="end">{v:.2f}</text>')
    out.append(f'<line x1="{L}" y1="{Y(v)}" x2="{W-RM}" y2="{Y(v)}" stroke="#dddddd"/>')
for t, label in [(T_PRESS, "held"), (T_SLIDE, "slid")]:
    out.append(f'<line x1="{X(t)}" y1="{T}" x2="{X(t)}" y2="{H-B}" stroke="#999999" stroke-dasharray="2,3"/>')
    out.append(f'<text x="{X(t)+4}" y="{H-B-6}" fill="#666666">{label}</text>')
out.append(f'<text x="{(L+W-RM)/2}" y="{H-12}" text-anchor="middle">time t</text>')
out.append(f'<text x="16" y="{(T+H-B)/2}" transform="rotate(-90 16 {(T+H-B)/2})" text-anchor="middle">force on the punch (per unit thickness)</text>')
for f, label, below in [(F_0, "F₀: the pad elastic with G(0)", 0), (F_INF, "F∞: the pad elastic with G∞", 1)]:
    out.append(f'<line x1="{L}" y1="{Y(f)}" x2="{W-RM}" y2="{Y(f)}" stroke="#555555" stroke-dasharray="6,4"/>')
    out.append(f'<text x="{W-RM-4}" y="{Y(f)+(17 if below else -5)}" text-anchor="end" fill="#555555">{label}</text>')
mu_n = " ".join(f"{X(t):.1f},{Y(MU * n):.1f}" for t, n in zip(times, normal))
out.append(f'<polyline points="{mu_n}" fill="none" stroke="#1f77b4" stroke-width="1.5" stroke-dasharray="5,3"/>')
for t, n, f in zip(times, normal, friction):
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(n):.1f}" r="3" fill="#d62728"/>')
    out.append(f'<circle cx="{X(t):.1f}" cy="{Y(f):.1f}" r="3" fill="none" stroke="#1f77b4" stroke-width="1.5"/>')
ly = Y(0.062)
out.append(f'<circle cx="{W-318}" cy="{ly}" r="3" fill="#d62728"/><text x="{W-298}" y="{ly+4}">normal force N (the pad on the punch)</text>')
out.append(f'<circle cx="{W-318}" cy="{ly+20}" r="3" fill="none" stroke="#1f77b4" stroke-width="1.5"/><text x="{W-298}" y="{ly+24}">friction force |T|</text>')
out.append(f'<line x1="{W-330}" y1="{ly+40}" x2="{W-305}" y2="{ly+40}" stroke="#1f77b4" stroke-width="1.5" stroke-dasharray="5,3"/><text x="{W-298}" y="{ly+44}">μN</text>')
out.append("</svg>")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
held = times.index(min(times, key=lambda t: abs(t - T_SLIDE)))
print(f"wrote {sys.argv[2]}: N({T_PRESS:g}) = {normal[times.index(min(times, key=lambda t: abs(t - T_PRESS)))]:.5f}, "
      f"N({T_SLIDE:g}) = {normal[held]:.5f}, T/N at t = {t_end:g}: {friction[-1] / normal[-1]:.6f}")
