#!/usr/bin/env python3
"""The PETSc backend against faer and against itself on 1 and 2 ranks (README "Running on a
cluster", docs/method.md §13.5): the 3D slab box:2n x n x n/4 with examples/slab.toml, whole
processes, interleaved, each run's peak memory per rank (VmHWM through /usr/bin/time -f %M, one
line per rank) and its phases from summary.json; and `hvi check --backend petsc`'s predicted
memory per rank for the same problem.

    python3 benches/petsc_scaling.py --hvi target/release/hvi --n 24 32 --ranks 1 2 \
        --repeats 2 --steps 8 [--blas /path/to/openblas-serial] [--before OLD_HVI]

--patch puts Γ₃ on a patch of the bottom only (the slab's y = 0 face where x ≥ 2 − w/n, all z,
w = round(n/8) cells wide: m = (w + 1)(n/4 + 1) contact nodes instead of (2n + 1)(n/4 + 1)), on
the same slab written as an MSH 2.2 file (the groups of box:, src/mesh/structured.rs), so that
W's m MUMPS solves stay affordable at ≥ 2·10⁵ unknowns. The README's scaling table
(docs/method.md §13.5) is

    python3 benches/petsc_scaling.py --patch --n 24 32 52 --ranks 1 2 --repeats 2 --steps 8 \
        --lock /tmp/hvi-cpu.lock

(--lock wraps every timed run in `flock -x LOCK`, so that no other heavy job runs beside it).

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


MESHES = {}


def patch_mesh(n, directory):
    """The slab box:2n x n x n/4 (cubic cells of size 1/n, the groups of src/mesh/structured.rs)
    as an MSH 2.2 file whose Gamma3 is only the bottom's last w = round(n/8) columns of cells."""
    nx, ny, nz = 2 * n, n, n // 4
    w = max(1, round(n / 8))
    h = 1.0 / ny
    path = os.path.join(directory, f"slab_patch_{n}.msh")
    nid = lambda i, j, k: 1 + i + (nx + 1) * (j + (ny + 1) * k)
    out = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$PhysicalNames", "5",
           '2 1 "Gamma1"', '2 2 "Gamma2"', '2 3 "Gamma3"', '2 6 "Sides"', '3 5 "Omega"', "$EndPhysicalNames",
           "$Nodes", str((nx + 1) * (ny + 1) * (nz + 1))]
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                out.append(f"{nid(i, j, k)} {i * h!r} {j * h!r} {k * h!r}")
    out.append("$EndNodes")
    quads = []  # (physical tag, four nodes)
    for j in range(ny):
        for k in range(nz):
            quads.append((1, [nid(0, j, k), nid(0, j, k + 1), nid(0, j + 1, k + 1), nid(0, j + 1, k)]))
            quads.append((2, [nid(nx, j, k), nid(nx, j + 1, k), nid(nx, j + 1, k + 1), nid(nx, j, k + 1)]))
    for i in range(nx):
        for k in range(nz):
            quads.append((2, [nid(i, ny, k), nid(i, ny, k + 1), nid(i + 1, ny, k + 1), nid(i + 1, ny, k)]))
            if i >= nx - w:
                quads.append((3, [nid(i, 0, k), nid(i + 1, 0, k), nid(i + 1, 0, k + 1), nid(i, 0, k + 1)]))
        for j in range(ny):
            quads.append((6, [nid(i, j, 0), nid(i, j + 1, 0), nid(i + 1, j + 1, 0), nid(i + 1, j, 0)]))
            quads.append((6, [nid(i, j, nz), nid(i + 1, j, nz), nid(i + 1, j + 1, nz), nid(i, j + 1, nz)]))
    hexes = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                hexes.append([nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k),
                              nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1), nid(i, j + 1, k + 1)])
    out += ["$Elements", str(len(quads) + len(hexes))]
    e = 0
    for tag, q in quads:
        e += 1
        out.append(f"{e} 3 2 {tag} {tag} " + " ".join(map(str, q)))
    for c in hexes:
        e += 1
        out.append(f"{e} 5 2 5 5 " + " ".join(map(str, c)))
    out.append("$EndElements")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    return path


def mesh_for(n):
    if PATCH is None:
        return f"box:{2 * n}x{n}x{n // 4}"
    if n not in MESHES:
        MESHES[n] = patch_mesh(n, PATCH)
    return MESHES[n]


PATCH = None  # the directory of the patch meshes with --patch


def scene_args(n, steps):
    return [mesh_for(n), "--scene", "examples/slab.toml", "--quiet",
            "--set", f"time.steps={steps}", "--set", f"output.every={steps}"]


def env_with(blas):
    env = dict(os.environ)
    env.pop("PETSC_OPTIONS", None)
    if blas:
        env["LD_LIBRARY_PATH"] = blas + (":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    return env


LOCK = []  # ["flock", "-x", LOCK] with --lock


def run(hvi, n, steps, np_, blas, out, extra=()):
    args = ["solve", *scene_args(n, steps), *extra, "--out", out]
    time = ["/usr/bin/time", "-f", "rank-peak-kb %M"]
    if np_ == 0:
        cmd = LOCK + time + [hvi, *args]
    else:
        cmd = LOCK + MPIRUN + ["-x", "LD_LIBRARY_PATH", "-np", str(np_)] + time + [hvi, *args, "--backend", "petsc"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env_with(blas))
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    peaks = [int(k) / 1024 for k in re.findall(r"rank-peak-kb (\d+)", p.stderr)]
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    ph = s["phases"]
    per_step = (ph["loads"] + ph["history"] + ph["forward_sweep"] + ph["contact"] + ph["backward_sweep"]) / s["steps"]
    return s, (ph["factorisation"], ph["condensation"]), per_step, ph["total"], peaks


def solves_per_step(name, s):
    """Distributed solves per step (docs/method.md §13): 1 with the stored responses, 2 with a
    recovery solve; faer's split sweeps are one solve."""
    if name == "faer":
        return 1
    return 1 if "stored responses" in (s.get("condensation") or "") else 2


def predicted(hvi, n, steps, np_, blas):
    cmd = MPIRUN + ["-x", "LD_LIBRARY_PATH", "-np", str(np_), hvi, "check", *scene_args(n, steps)[:3],
                    "--set", f"time.steps={steps}", "--backend", "petsc"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env_with(blas))
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    rows = []
    entries = re.search(r"about (\d+) factor entries", p.stdout)
    lines = p.stdout.splitlines()
    start = next(i for i, l in enumerate(lines) if l.strip().startswith("rank "))
    for l in lines[start + 1:]:
        if not l.strip() or not l.strip()[0].isdigit():
            break
        rows.append([float(w) for w in l.replace("|", " ").split()])
    return rows, int(entries.group(1)) if entries else 0


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
    ap.add_argument("--patch", action="store_true", help="Γ₃ on a patch of the bottom only (see above)")
    ap.add_argument("--lock", help="wrap every timed run in flock -x LOCK")
    ap.add_argument("--recovery-solve", action="store_true",
                    help="also run the PETSc backend forced to a recovery solve per step (solver.condensation = "
                         "\"recovery_solve\", docs/method.md §13), as runs petsc2-npP, interleaved")
    a = ap.parse_args()
    global PATCH, LOCK
    if a.lock:
        LOCK = ["flock", "-x", a.lock]
    if a.patch:
        PATCH = tempfile.mkdtemp(prefix="hvi-patch-")
    print("n,unknowns,contact_nodes,run,repeat,factor_s,w_s,per_step_s,total_s,peak_mib_max_rank,peak_mib_per_rank,"
          "predicted_mib_max_rank,mumps_factor_entries,mumps_factor_mb_per_rank,solves_per_step")
    configs = ([] if a.no_faer else [("faer", a.hvi, 0, ())]) + [(f"petsc-np{r}", a.hvi, r, ()) for r in a.ranks]
    if a.recovery_solve:
        forced = ("--set", 'solver.condensation="recovery_solve"')
        configs += [(f"petsc2-np{r}", a.hvi, r, forced) for r in a.ranks]
    if a.before:
        configs += [(f"before-np{r}", a.before, r, ()) for r in a.ranks]
    predictions = {}
    for rep in range(a.repeats):
        for n in a.n:
            for name, hvi, np_, extra in configs:
                with tempfile.TemporaryDirectory() as d:
                    s, setup, step, total, peaks = run(hvi, n, a.steps, np_, a.blas, os.path.join(d, "run"), extra)
                pred, entries, mumps = "", "", ""
                if name.startswith("petsc-np"):
                    key = (n, np_)
                    if key not in predictions:
                        predictions[key] = predicted(hvi, n, a.steps, np_, a.blas)
                    rows, entries = predictions[key]
                    pred = f"{max(r[-1] for r in rows):.0f}"
                    mumps = "/".join(str(r.get("mumps_factor_mb")) for r in s.get("per_rank", []))
                print(f"{n},{s['unknowns']},{s['contact_nodes']},{name},{rep},{setup[0]:.2f},{setup[1]:.2f},{step:.4f},"
                      f"{total:.2f},{max(peaks):.0f},{'/'.join(f'{p:.0f}' for p in peaks)},{pred},{entries},{mumps},"
                      f"{solves_per_step(name, s)}", flush=True)


if __name__ == "__main__":
    main()
