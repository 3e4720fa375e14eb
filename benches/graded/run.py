"""The graded tetrahedral blocks of issue 46 (graded_block.geo, graded_block.toml): whole runs of
hvi, interleaved, with nnz(L), factorisation, condensation and whole-process time per size, and
optionally the same beside an older binary. CHOLMOD's side on the same matrices is the strong
peer benches/factor_vs_cholmod_3d.rs, which this script runs with --cholmod.

    python3 benches/graded/run.py HVI [--against OLD_HVI] [--sizes 31k,100k,300k] [--rounds 3]
                                      [--cholmod] [--dir DIR]

Meshes are made with gmsh (`pip install gmsh`) into DIR (default /tmp/hvi_graded) when missing:

| size | hf     | s     | nodes  | unknowns | contact nodes |
|------|--------|-------|--------|----------|---------------|
| 31k  | 0.008  | 0.09  |  9 882 |   29 646 | 1 656 |
| 100k | 0.0054 | 0.06  | 30 720 |   92 160 | 3 594 |
| 300k | 0.0038 | 0.042 | 85 560 |  256 680 | 7 223 |

(counts from gmsh 4.15.2; another gmsh may mesh a little differently). Each round runs every
(size, binary) once, the order rotated per round; medians per (size, binary) are printed with the
phases of summary.json. --cholmod then runs `cargo bench --bench factor_vs_cholmod_3d` on the
meshes (CHOLMOD through scikit-sparse: `pip install "scikit-sparse<0.5"`, Debian's
libsuitesparse-dev) and prints its table for each.
"""
import argparse
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
SIZES = {"31k": (0.008, 0.09), "100k": (0.0054, 0.06), "300k": (0.0038, 0.042)}
SCENE = HERE / "graded_block.toml"


def mesh(size, directory):
    path = directory / f"graded_{size}.msh"
    if not path.exists():
        gmsh = shutil.which("gmsh")
        if gmsh is None:
            sys.exit("gmsh not found: pip install gmsh")
        hf, s = SIZES[size]
        subprocess.run([gmsh, "-3", str(HERE / "graded_block.geo"), "-setnumber", "hf", str(hf),
                        "-setnumber", "s", str(s), "-format", "msh41", "-o", str(path)],
                       check=True, stdout=subprocess.DEVNULL)
    return path


def run(binary, msh, out):
    start = time.perf_counter()
    subprocess.run([binary, "solve", str(msh), "--scene", str(SCENE), "--out", str(out),
                    "--overwrite", "--quiet"], check=True)
    wall = time.perf_counter() - start
    summary = json.loads((out / "summary.json").read_text())
    return wall, summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("hvi")
    ap.add_argument("--against")
    ap.add_argument("--sizes", default="31k,100k")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cholmod", action="store_true")
    ap.add_argument("--dir", default="/tmp/hvi_graded")
    args = ap.parse_args()
    directory = pathlib.Path(args.dir)
    directory.mkdir(parents=True, exist_ok=True)
    sizes = [s.strip() for s in args.sizes.split(",")]
    meshes = {s: mesh(s, directory) for s in sizes}
    binaries = {"new": args.hvi} | ({"old": args.against} if args.against else {})
    jobs = [(s, b) for s in sizes for b in binaries]
    results = {job: [] for job in jobs}
    for r in range(args.rounds):
        for k in range(len(jobs)):
            size, name = jobs[(k + r) % len(jobs)]
            wall, summary = run(binaries[name], meshes[size], directory / f"out_{size}_{name}")
            results[(size, name)].append((wall, summary))
            print(f"round {r + 1} {size:5} {name}: {wall:7.2f} s", flush=True)
    print(f"\n{'size':5} {'binary':6} {'unknowns':>9} {'m':>6} {'nnz(L)':>9} {'factor s':>9} "
          f"{'cond. s':>8} {'factor+cond':>11} {'whole s':>8} {'min s':>7}")
    for size, name in jobs:
        runs = results[(size, name)]
        s = runs[0][1]
        med = lambda key: statistics.median(r[1]["phases"][key] for r in runs)
        walls = [r[0] for r in runs]
        print(f"{size:5} {name:6} {s['unknowns']:>9} {s['contact_nodes']:>6} "
              f"{s['factor_entries'] / 1e6:>8.1f}M {med('factorisation'):>9.2f} {med('condensation'):>8.2f} "
              f"{statistics.median(r[1]['phases']['factorisation'] + r[1]['phases']['condensation'] for r in runs):>11.2f} "
              f"{statistics.median(walls):>8.2f} {min(walls):>7.2f}")
    if args.against:
        for size in sizes:
            new = statistics.median(r[0] for r in results[(size, "new")])
            old = statistics.median(r[0] for r in results[(size, "old")])
            print(f"{size}: old / new = {old / new:.2f} (whole process, medians)")
    if args.cholmod:
        env = dict(os.environ, HVI_BENCH_MESH=",".join(str(meshes[s]) for s in sizes),
                   HVI_BENCH_SCENE=str(SCENE), HVI_BENCH_REPEATS=os.environ.get("HVI_BENCH_REPEATS", "3"))
        subprocess.run(["cargo", "bench", "--bench", "factor_vs_cholmod_3d"], cwd=ROOT, env=env, check=True)


if __name__ == "__main__":
    main()
