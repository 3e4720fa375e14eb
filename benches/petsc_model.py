#!/usr/bin/env python3
"""The scaling model of the PETSc backend (docs/method.md §13.5, README "Running on a cluster"):
calibrated on the smaller runs of a benches/petsc_scaling.py CSV, then its predictions set
against the larger runs of the same CSV.

    python3 benches/petsc_scaling.py --patch --n 24 28 32 52 ... > runs.csv
    python3 benches/petsc_model.py runs.csv --calibrate 24 28 32 [--predict-unknowns 1e6 ...]

The model, per rank, for n unknowns, m contact nodes, P ranks (max over the ranks):

    nnz(L)(n)  = κ n^α                     (MUMPS's analysis, INFOG(3), fitted on the calibration)
    memory     = a + b n + (c n + d ι_P nnz(L)) / P + 32 m² [rank 0]   (bytes → MiB)
    time/step  = e_P + s_P (j nnz(L) + z n m) / P
                 (j distributed solves per step: 1 with the stored responses Z = K⁻¹Cᵀ, whose
                 product u_free − Zλ reads z n m numbers (z = 1), 2 with a recovery solve (z = 0);
                 docs/method.md §13)
    setup      = φ_P n^β                    (the factor and W's ⌈m/32⌉ blocks of 32 solves)

d from MUMPS's factor memory per entry (INFO(16) over INFOG(3)), ι_P its largest rank's share
over the mean, a … c from the peak memory (VmHWM) of the calibration runs on 1 and 2 ranks (least
squares; for P beyond the measured, ι of the largest P measured), s_P
and e_P from their time per step on P ranks (for P beyond the measured: s_1 and e_1, i.e. ideal
division of the solves, dedicated cores), φ_P, β from their setup time (for P beyond the
measured: φ_1/P).
"""

import argparse
import csv
import math
from collections import defaultdict

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv", help="the runs: calibration and prediction")
    ap.add_argument("analyses", nargs="*",
                    help="more CSVs of the same family whose MUMPS analyses (deterministic: nnz(L) only, no "
                         "timings) join the fit of nnz(L) at sizes up to the largest calibration n")
    ap.add_argument("--calibrate", type=int, nargs="+", required=True, help="the n of the calibration runs")
    ap.add_argument("--predict-unknowns", type=float, nargs="*", default=[],
                    help="also print the model's figures at these unknowns (slab family, m = contact nodes of the patch)")
    ap.add_argument("--ranks", type=int, nargs="*", default=[1, 2, 64, 256, 1024])
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.csv)))
    more = [r for f in a.analyses for r in csv.DictReader(open(f))]
    # medians over repeats, per (n, run)
    groups = defaultdict(list)
    for r in rows:
        groups[(int(r["n"]), r["run"])].append(r)
    med = {}
    for key, rs in groups.items():
        def m(col):
            v = [float(r[col]) for r in rs if r[col] not in ("", "None")]
            return float(np.median(v)) if v else float("nan")
        med[key] = {
            "unknowns": int(rs[0]["unknowns"]), "m": int(rs[0]["contact_nodes"]),
            "factor": m("factor_s"), "w": m("w_s"), "step": m("per_step_s"), "peak": m("peak_mib_max_rank"),
            "pred": m("predicted_mib_max_rank"), "entries": m("mumps_factor_entries"), "runs": len(rs),
            # older CSVs (before the stored responses) have no column: two solves per step
            "solves": int(rs[0].get("solves_per_step") or 2),
        }
    petsc = {k: v for k, v in med.items() if k[1].startswith("petsc-np")}
    ranks = lambda run: int(run[len("petsc-np"):])
    cal = {k: v for k, v in petsc.items() if k[0] in a.calibrate}
    # nnz(L) = κ n^α from the 1-rank analyses (MUMPS's INFOG(3): a symbolic count, the same on
    # every machine), of the calibration runs and of the other CSVs up to the largest calibration n
    pts = sorted({(v["unknowns"], v["entries"]) for k, v in cal.items() if ranks(k[1]) == 1} |
                 {(int(r["unknowns"]), float(r["mumps_factor_entries"])) for r in rows + more
                  if r["run"] == "petsc-np1" and r["mumps_factor_entries"] and int(r["n"]) <= max(a.calibrate)})
    A = np.array([[1.0, math.log(u)] for u, _ in pts])
    coef = np.linalg.lstsq(A, np.array([math.log(e) for _, e in pts]), rcond=None)[0]
    kappa, alpha = math.exp(coef[0]), coef[1]
    nnz = lambda n: kappa * n ** alpha
    print(f"nnz(L) = {kappa:.4g} n^{alpha:.3f}  (fitted on {len(pts)} calibration sizes)")
    # memory: MUMPS's own bytes per factor entry (INFO(16) summed over the ranks / INFOG(3)) and
    # the largest rank's share of it (ι_P), then a, b, c by least squares on the rest
    per_entry, share = [], defaultdict(list)
    for (n, run), v in cal.items():
        P = ranks(run)
        for r in groups[(n, run)]:
            mb = [float(x) for x in r["mumps_factor_mb_per_rank"].split("/") if x not in ("", "None")]
            if mb and v["entries"] > 0:
                per_entry.append(sum(mb) * 1e6 / 2**20 / v["entries"])
                share[P].append(max(mb) / (sum(mb) / P))
    d = float(np.median(per_entry))
    iota = {P: float(np.median(v)) for P, v in share.items()}
    X, y = [], []
    for (n, run), v in cal.items():
        P, u = ranks(run), v["unknowns"]
        X.append([1.0, u, u / P])
        y.append(v["peak"] - 32 * v["m"] ** 2 / 2**20 - d * iota[P] * nnz(u) / P)
    mem = np.linalg.lstsq(np.array(X), np.array(y), rcond=None)[0]
    print(f"memory [MiB] = {mem[0]:.1f} + {mem[1] * 2**20:.0f} B · n + ({mem[2] * 2**20:.0f} B · n + "
          f"{d * 2**20:.2f} B · ι_P nnz(L)) / P + 32 m² B on rank 0;  ι = " +
          ", ".join(f"{iota[P]:.3f} (P = {P})" for P in sorted(iota)))
    memory = lambda u, m, P: (mem[0] + mem[1] * u + (mem[2] * u + d * iota.get(P, max(iota.values())) * nnz(u)) / P
                              + 32 * m * m / 2**20)
    # time per step: e_P + s_1 (j nnz(L) + z n m)/P. s_1 and e_1 from the 1-rank runs (least
    # squares); for P > 1 the work divides ideally (s_P = s_1, the assumption of every
    # extrapolation to more ranks) and e_P, what a step on P ranks costs beyond its share of the
    # work (the reductions, the separators' traffic, rank 0's contact solve), is the mean excess
    # of its calibration runs.
    Ps = sorted({ranks(k[1]) for k in cal})
    work = lambda u, m, j, P: (j * nnz(u) + (u * m if j == 1 else 0.0)) / P
    one = [(work(v["unknowns"], v["m"], v["solves"], 1), v["step"]) for k, v in cal.items() if ranks(k[1]) == 1]
    s1, e1 = np.polyfit([x for x, _ in one], [t for _, t in one], 1)
    e = {1: e1}
    for P in Ps[1:]:
        excess = [v["step"] - s1 * work(v["unknowns"], v["m"], v["solves"], P) for k, v in cal.items() if ranks(k[1]) == P]
        e[P] = float(np.mean(excess))
    print(f"time/step [s] = e_P + s_1 (j nnz(L) + z n m) / P: s_1 = {s1:.3g} s per entry, " + ", ".join(
        f"e_{P} = {e[P]*1e3:.1f} ms" for P in Ps))
    step = lambda u, m, j, P: e.get(P, max(e.values())) + s1 * work(u, m, j, P)
    # the setup (the factor and W: PETSc's factorisation phase includes W), φ_P n^β per P
    setup_fit = {}
    for P in Ps:
        pts = [(math.log(v["unknowns"]), math.log(v["factor"] + v["w"])) for k, v in cal.items() if ranks(k[1]) == P]
        beta, lphi = np.polyfit([x for x, _ in pts], [t for _, t in pts], 1)
        setup_fit[P] = (math.exp(lphi), beta)
    print("setup (factor + W) [s] = " + ", ".join(f"P = {P}: {f:.3g} n^{b:.2f}" for P, (f, b) in setup_fit.items()))
    setup = lambda u, P: (setup_fit[P][0] if P in setup_fit else setup_fit[1][0] / P) * u ** setup_fit.get(P, setup_fit[1])[1]
    print()
    print("n,unknowns,m,run,measured_peak_mib,model_peak_mib,error,check_mib,measured_step_s,model_step_s,error,"
          "measured_setup_s,model_setup_s,measured_entries,model_entries")
    for (n, run), v in sorted(petsc.items()):
        P, u = ranks(run), v["unknowns"]
        mp, ms = memory(u, v["m"], P), step(u, v["m"], v["solves"], P)
        tag = "calibration" if n in a.calibrate else "prediction"
        print(f"{n},{u},{v['m']},{run} ({tag}),{v['peak']:.0f},{mp:.0f},{(mp - v['peak']) / v['peak']:+.1%},{v['pred']:.0f},"
              f"{v['step']:.4f},{ms:.4f},{(ms - v['step']) / v['step']:+.1%},{v['factor'] + v['w']:.2f},{setup(u, P):.2f},"
              f"{v['entries']:.0f},{nnz(u):.0f}")
    for (n, run), v in sorted(med.items()):
        if run == "faer" and ("petsc-np1" in [k[1] for k in petsc if k[0] == n]):
            p1 = petsc[(n, "petsc-np1")]
            print(f"overhead n={n} ({v['unknowns']} unknowns): MUMPS 1 rank {p1['step']*1e3:.1f} ms/step, faer "
                  f"{v['step']*1e3:.1f} ms/step: {p1['step'] / v['step']:.2f}x; peak {p1['peak']:.0f} / {v['peak']:.0f} MiB")
    for u in a.predict_unknowns:
        # the patch family: n from unknowns ≈ 3 (2n+1)(n+1)(n/4+1), m = (round(n/8)+1)(n/4+1)
        n = round((4 * u / 6) ** (1 / 3))
        m = (max(1, round(n / 8)) + 1) * (n // 4 + 1)
        for P in a.ranks:
            print(f"model at {u:.3g} unknowns (n ≈ {n}, m = {m}), P = {P}: nnz(L) {nnz(u):.3g}, memory "
                  f"{memory(u, m, P):.0f} MiB per rank, step {step(u, m, 1, P):.3g} s, "
                  f"setup {setup(u, P):.3g} s (one solve per step; {step(u, m, 2, P):.3g} s with a recovery solve)")


if __name__ == "__main__":
    main()
