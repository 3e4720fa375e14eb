#!/usr/bin/env python3
"""The PETSc backend against faer and against itself on 1 and 2 ranks (README "Running on a
cluster", docs/method.md §13.5): the 3D slab box:2n x n x n/4 with examples/slab.toml, whole
processes, interleaved, each run's peak memory per rank (VmHWM through /usr/bin/time -f %M, one
line per rank) and its phases from summary.json; and `hvi check --backend petsc`'s predicted
memory per rank for the same problem.

    python3 benches/petsc_scaling.py --hvi target/release/hvi --n 24 32 --ranks 1 2 \
        --repeats 2 --steps 8 [--blas /path/to/openblas-serial] [--before OLD_HVI]

Prints one CSV row per run: n, unknowns, contact nodes, which (faer, petsc-np1, ...), repeat,
setup seconds (factorisation phase: the factor and W), seconds per step (loads, history,
solves, contact over the steps), total, peak MiB per rank (max over ranks), and for PETSc the
check's predicted MiB per rank (max over ranks). --before runs an older hvi's PETSc backend too
(before/after memory). Needs the `petsc` feature's binary and Open MPI's mpirun.
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

MPIRUN = ["mpirun", "--allow-run-as-root", "--oversubscribe", "--mca", "mpi_yield_when_idle", "1"]


def scene_args(n, steps):
    return [f"box:{2 * n}x{n}x{n // 4}", "--scene", "examples/slab.toml", "--quiet",
            "--set", f"time.steps={steps}", "--set", f"output.every={steps}"]


def env_with(blas):
    env = dict(os.environ)
    env.pop("PETSC_OPTIONS", None)
    if blas:
        env["LD_LIBRARY_PATH"] = blas + (":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    return env


def run(hvi, n, steps, np_, blas, out):
    args = ["solve", *scene_args(n, steps), "--out", out]
    time = ["/usr/bin/time", "-f", "rank-peak-kb %M"]
    if np_ == 0:
        cmd = time + [hvi, *args]
    else:
        cmd = MPIRUN + ["-x", "LD_LIBRARY_PATH", "-np", str(np_)] + time + [hvi, *args, "--backend", "petsc"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env_with(blas))
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    peaks = [int(k) / 1024 for k in re.findall(r"rank-peak-kb (\d+)", p.stderr)]
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    ph = s["phases"]
    per_step = (ph["loads"] + ph["history"] + ph["forward_sweep"] + ph["contact"] + ph["backward_sweep"]) / s["steps"]
    return s, ph["factorisation"] + ph["condensation"], per_step, ph["total"], peaks


def predicted(hvi, n, steps, np_, blas):
    cmd = MPIRUN + ["-x", "LD_LIBRARY_PATH", "-np", str(np_), hvi, "check", *scene_args(n, steps)[:3],
                    "--set", f"time.steps={steps}", "--backend", "petsc"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env_with(blas))
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    rows = []
    lines = p.stdout.splitlines()
    start = next(i for i, l in enumerate(lines) if l.strip().startswith("rank "))
    for l in lines[start + 1:]:
        if not l.strip() or not l.strip()[0].isdigit():
            break
        rows.append([float(w) for w in l.replace("|", " ").split()])
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--hvi", default="target/release/hvi")
    ap.add_argument("--before", help="an older hvi (petsc feature) whose PETSc runs to measure too")
    ap.add_argument("--n", type=int, nargs="+", default=[24, 32])
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--steps", type=int, default=8)
    ap.add_argument("--blas", help="a directory holding the libblas.so.3/liblapack.so.3 to load (LD_LIBRARY_PATH)")
    ap.add_argument("--no-faer", action="store_true")
    a = ap.parse_args()
    print("n,unknowns,contact_nodes,run,repeat,setup_s,per_step_s,total_s,peak_mib_max_rank,peak_mib_per_rank,predicted_mib_max_rank")
    configs = ([] if a.no_faer else [("faer", a.hvi, 0)]) + [(f"petsc-np{r}", a.hvi, r) for r in a.ranks]
    if a.before:
        configs += [(f"before-np{r}", a.before, r) for r in a.ranks]
    predictions = {}
    for rep in range(a.repeats):
        for n in a.n:
            for name, hvi, np_ in configs:
                with tempfile.TemporaryDirectory() as d:
                    s, setup, step, total, peaks = run(hvi, n, a.steps, np_, a.blas, os.path.join(d, "run"))
                pred = ""
                if name.startswith("petsc"):
                    key = (n, np_)
                    if key not in predictions:
                        predictions[key] = predicted(hvi, n, a.steps, np_, a.blas)
                    pred = f"{max(r[-1] for r in predictions[key]):.0f}"
                print(f"{n},{s['unknowns']},{s['contact_nodes']},{name},{rep},{setup:.2f},{step:.4f},{total:.2f},"
                      f"{max(peaks):.0f},{'/'.join(f'{p:.0f}' for p in peaks)},{pred}", flush=True)


if __name__ == "__main__":
    main()
