"""Whole-process wall time and peak memory of an hvi command line against the 3D numpy/scipy/CHOLMOD
reference (benches/numpy_reference_3d.py) on the 3D slab, interleaved.

    python3 benches/whole_run_vs_numpy_3d.py --n 32 --hvi "target/release/hvi solve meshes/slab_n32.msh \
        --scene examples/slab.toml --out /tmp/x --overwrite --quiet" [--repeats 3] [--steps 32] [--numpy-args "..."] \
        [--compare /tmp/x]

Each repeat runs the reference (`numpy_reference_3d.py --n N --steps S --save FILE`) and then the hvi
command, each as a child process; its wall time is taken around the process and its peak resident
set is GNU time's %M (/usr/bin/time -v's "Maximum resident set size"), or the kernel's rusage of
the child (os.wait4) where /usr/bin/time is missing. Prints every run, the medians and the ratios numpy/hvi. With --compare (hvi's
output folder, whose last solution_*.vtu has a "displacement" point array, or a .npy of shape
(nodes, 3)) it also prints max |u_hvi - u_numpy| / max |u_hvi| at t = T; node order i + (2n+1)(j +
(n+1)k), as numpy_reference_3d.py saves it. Needs numpy (and what numpy_reference_3d.py needs).
"""
import argparse
import os
import pathlib
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
TIME = "/usr/bin/time" if os.access("/usr/bin/time", os.X_OK) else None


def run(cmd, quiet=True):
    """(wall seconds, peak RSS in MiB) of one child process; raises if it fails. Under GNU time
    (/usr/bin/time, when there) for the peak RSS, else from os.wait4's rusage of the child, which
    also counts the forked Python before its exec (some 15 MiB)."""
    out = subprocess.DEVNULL if quiet else None
    with tempfile.NamedTemporaryFile("r", suffix=".rss") as rss:
        timed = [TIME, "-f", "%M", "-o", rss.name] + cmd if TIME else cmd
        t = time.perf_counter()
        proc = subprocess.Popen(timed, stdout=out)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t
        proc.returncode = os.waitstatus_to_exitcode(status)
        if proc.returncode:
            raise SystemExit(f"failed ({proc.returncode}): {shlex.join(cmd)}")
        kib = int(rss.read().split()[-1]) if TIME else usage.ru_maxrss  # Linux: KiB
    return wall, kib / 1024


def final_displacement(path):
    """Nodes x 3 from a .npy or from the last solution_*.vtu of an hvi output folder."""
    import numpy as np
    path = pathlib.Path(path)
    if path.suffix == ".npy":
        return np.load(path)
    sys.path.insert(0, str(HERE))
    from whole_run_vs_numpy import vtu_array  # the 2D harness's reader of hvi's .vtu
    frames = sorted(path.glob("solution_*.vtu")) if path.is_dir() else [path]
    if not frames:
        raise SystemExit(f"{path}: no solution_*.vtu")
    return vtu_array(frames[-1], "displacement")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=32, help="cells per unit length of the slab")
    ap.add_argument("--steps", type=int, default=32)
    ap.add_argument("--hvi", required=True, help="the hvi command line, one shell-quoted string")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--numpy-args", default="", help="extra arguments for numpy_reference_3d.py")
    ap.add_argument("--compare", help="hvi's output folder (or a .npy) to compare displacements with")
    ap.add_argument("--show", action="store_true", help="let both print (default: quiet)")
    args = ap.parse_args()
    hvi_cmd = shlex.split(args.hvi)
    with tempfile.TemporaryDirectory(prefix="hvi-vs-numpy-3d-") as tmp:
        saved = pathlib.Path(tmp) / "numpy_u.npy"
        np_cmd = [sys.executable, str(HERE / "numpy_reference_3d.py"), "--n", str(args.n),
                  "--steps", str(args.steps), "--save", str(saved)] + shlex.split(args.numpy_args)
        print(f"numpy: {shlex.join(np_cmd)}\nhvi:   {shlex.join(hvi_cmd)}", flush=True)
        res = {"numpy": [], "hvi": []}
        for i in range(args.repeats):
            res["numpy"].append(run(np_cmd, not args.show))
            res["hvi"].append(run(hvi_cmd, not args.show))
            print(f"run {i + 1}: numpy {res['numpy'][-1][0]:.3f} s {res['numpy'][-1][1]:.0f} MiB, "
                  f"hvi {res['hvi'][-1][0]:.3f} s {res['hvi'][-1][1]:.0f} MiB", flush=True)
        med = {k: [statistics.median(x[j] for x in v) for j in range(2)] for k, v in res.items()}
        print(f"median wall: numpy {med['numpy'][0]:.3f} s, hvi {med['hvi'][0]:.3f} s, "
              f"ratio numpy/hvi {med['numpy'][0] / med['hvi'][0]:.2f}")
        print(f"median max RSS: numpy {med['numpy'][1]:.0f} MiB, hvi {med['hvi'][1]:.0f} MiB, "
              f"ratio numpy/hvi {med['numpy'][1] / med['hvi'][1]:.2f}")
        if args.compare:
            u_np, u_hvi = final_displacement(saved), final_displacement(args.compare)
            if u_np.shape != u_hvi.shape:
                raise SystemExit(f"shapes differ: numpy {u_np.shape}, hvi {u_hvi.shape}")
            diff = abs(u_hvi - u_np).max() / abs(u_hvi).max()
            print(f"final displacement: max|u_hvi - u_numpy| / max|u_hvi| = {diff:.2e}")
            return 0 if diff < 1e-6 else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
