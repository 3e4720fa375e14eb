"""Whole-process wall time of two hvi binaries on the paper's example, interleaved (A, B, A, B, …),
and a check that both give the same final displacement: the performance floor "nothing here
slows the paper's example" (issue 10: h = k = 1/128 within 5 % of before).

    python3 benches/whole_run_ab.py OLD_HVI NEW_HVI [NX NY STEPS] [--repeats R]

Defaults 256 128 128 (h = k = 1/128, only the last frame written), R = 5. Each run is
`hvi solve rect:NXxNY --set time.steps=STEPS --set output.every=STEPS --out DIR --quiet` into a
fresh directory. Prints each pair, the medians, NEW/OLD, and max |u_new − u_old| / max |u_old| at
t = T. Needs numpy (for reading the .vtu files with benches/whole_run_vs_numpy.py's reader).
"""
import argparse
import pathlib
import shutil
import statistics
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from whole_run_vs_numpy import hvi_final, timed  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("sizes", nargs="*", type=int, default=[256, 128, 128], help="NX NY STEPS")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    nx, ny, steps = args.sizes
    with tempfile.TemporaryDirectory(prefix="hvi-ab-") as tmp:
        tmp = pathlib.Path(tmp)

        def cmd(binary, out):
            return [binary, "solve", f"rect:{nx}x{ny}", "--set", f"time.steps={steps}",
                    "--set", f"output.every={steps}", "--out", str(out), "--quiet"]

        times = {"old": [], "new": []}
        for i in range(args.repeats):
            for name in ("old", "new"):
                out = tmp / name
                shutil.rmtree(out, ignore_errors=True)
                times[name].append(timed(cmd(getattr(args, name), out)))
            print(f"run {i + 1}: old {times['old'][-1]:.3f} s, new {times['new'][-1]:.3f} s", flush=True)
        m_old, m_new = statistics.median(times["old"]), statistics.median(times["new"])
        print(f"median of {args.repeats}: old {m_old:.3f} s (runs {min(times['old']):.3f}-{max(times['old']):.3f}), "
              f"new {m_new:.3f} s (runs {min(times['new']):.3f}-{max(times['new']):.3f}), new/old {m_new / m_old:.3f}")
        u_old, it_old = hvi_final(tmp / "old")
        u_new, it_new = hvi_final(tmp / "new")
        import numpy as np
        diff = np.abs(u_new - u_old).max() / np.abs(u_old).max()
        print(f"final displacement: max|u_new - u_old| / max|u_old| = {diff:.2e}; Newton iterations "
              f"old {sum(it_old)}, new {sum(it_new)}")
        return 0 if diff < 1e-8 else 1


if __name__ == "__main__":
    sys.exit(main())
