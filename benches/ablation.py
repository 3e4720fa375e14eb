"""What each strategy of the contact solve is worth (docs/ablation.md): whole runs of the cases the
strategies were introduced for, with every strategy on and with one switched off at a time
(`--set solver.without=["name"]`), interleaved round by round.

    python3 benches/ablation.py HVI [--rounds 3] [--only a,b+c] [--cases slab_coulomb,soft_layer]
                                [--csv ablation.csv]
    python3 benches/ablation.py HVI --against OLD_HVI [--rounds 5]    # two binaries, every strategy on
    python3 benches/ablation.py --table ablation.csv          # the medians as a Markdown table

Each round runs every (variant, case) pair once, the variants in an order rotated by one each
round (so that no variant always follows the same one); a row per run is appended to the CSV as it
ends (a stopped measurement keeps what it measured). A run without a strategy is compared with the
round's run with all of them (`--only a,b+c`: without a, then without both b and c): `diff` is max |Δ| / max |value| over gamma3.csv's numeric columns at
every written frame. Friction's strategies run only on the cases with friction.
"""
import argparse
import csv
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

SLAB_COULOMB = 'contact.friction={ kind = "coulomb", coefficient = 0.3 }'
CASES = {
    # the slab 80x40x10 with Coulomb friction (docs/method.md §17.8)
    "slab_coulomb": (["box:80x40x10", "--scene", "examples/slab.toml", "--set", SLAB_COULOMB,
                      "--set", "output.every=32"], True),
    # the soft layer at m = 4 096 (benches/soft_layer.toml, docs/method.md §9.2)
    "soft_layer": (["box:64x4x63", "--scene", "benches/soft_layer.toml", "--set", "time.steps=8",
                    "--set", "output.every=8"], False),
    # 3D Cattaneo-Mindlin, Coulomb mu = 0.6 (examples/gallery/cattaneo_3d)
    "cattaneo_3d": (["examples/gallery/cattaneo_3d/cattaneo_3d.msh", "--scene",
                     "examples/gallery/cattaneo_3d/cattaneo_3d.toml"], True),
    # 3D Hertz (examples/gallery/hertz_3d)
    "hertz_3d": (["examples/gallery/hertz_3d/hertz_3d.msh", "--scene",
                  "examples/gallery/hertz_3d/hertz_3d.toml"], False),
    # the paper's example at h = k = 1/128 (examples/paper.toml, the embedded default)
    "paper_128": (["rect:256x128", "--set", "time.steps=128", "--set", "output.every=128"], False),
    # the long-memory relaxation example (examples/gallery/relaxation)
    "relaxation": (["examples/gallery/relaxation/relaxation.msh", "--scene",
                    "examples/gallery/relaxation/relaxation.toml", "--set", "output.every=240"], False),
}
FRICTION_ONLY = {"branch_model", "coupled_step", "anderson", "load_predictor", "slip_predictor",
                 "unloaded_round", "inexact_rounds"}
STRATEGIES = ["kept_factor", "low_rank_update", "border", "jacobi_rows", "inexact_newton",
              "single_precision", "product_reuse", "system_in_w", "w_product", "recycled_storage", "branch_model",
              "watchdog", "round_off_acceptance", "enlarged_active_set", "kink_stops",
              "proximal_shift", "coupled_step", "anderson", "load_predictor", "slip_predictor",
              "unloaded_round", "inexact_rounds"]
FIELDS = ["round", "case", "variant", "seconds", "status", "newton_iterations", "contact_seconds",
          "diff"]


def gamma3(path):
    """The numeric columns of gamma3.csv, row by row."""
    rows = []
    with open(path) as f:
        for row in csv.reader(f):
            values = []
            for v in row:
                try:
                    values.append(float(v))
                except ValueError:
                    pass
            if values:
                rows.append(values)
    return rows


def difference(a, b):
    if len(a) != len(b):
        return float("inf")
    scale = max((abs(v) for row in a for v in row), default=0.0) or 1.0
    worst = 0.0
    for ra, rb in zip(a, b):
        if len(ra) != len(rb):
            return float("inf")
        worst = max(worst, max((abs(x - y) for x, y in zip(ra, rb)), default=0.0))
    return worst / scale


def run(hvi, case, variant, out, against=None):
    args, _ = CASES[case]
    command = [against if variant == "old" else hvi, "solve", *args, "--out", str(out), "--quiet"]
    if variant not in ("all", "old"):
        names = ", ".join(f'"{v}"' for v in variant.split("+"))
        command += ["--set", f"solver.without=[{names}]"]
    shutil.rmtree(out, ignore_errors=True)
    start = time.perf_counter()
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    seconds = time.perf_counter() - start
    status, iterations, contact = "failed", "", ""
    try:
        summary = json.loads((out / "summary.json").read_text())
        status = summary.get("status", "?") if done.returncode == 0 else "failed"
        iterations = summary.get("newton_iterations", "")
        contact = summary.get("phases", {}).get("contact", "")
    except (OSError, ValueError):
        pass
    if done.returncode != 0:
        print(f"  {case} without {variant}: exit {done.returncode}: {done.stderr.strip()[-300:]}", flush=True)
    return seconds, status, iterations, contact


def measure(args):
    variants = ["all"] + (["old"] if args.against else args.only or STRATEGIES)
    cases = [c for c in CASES if not args.cases or c in args.cases]
    new = not os.path.exists(args.csv)
    with open(args.csv, "a", newline="") as f, tempfile.TemporaryDirectory(prefix="hvi-ablation-") as tmp:
        tmp = pathlib.Path(tmp)
        writer = csv.DictWriter(f, FIELDS)
        if new:
            writer.writeheader()
        for r in range(args.rounds):
            order = variants[r % len(variants):] + variants[:r % len(variants)]
            for variant in order:
                for case in cases:
                    if set(variant.split("+")) <= FRICTION_ONLY and not CASES[case][1]:
                        continue
                    out = tmp / f"{case}-{variant}"
                    seconds, status, iterations, contact = run(args.hvi, case, variant, out, args.against)
                    writer.writerow({"round": r, "case": case, "variant": variant, "seconds": f"{seconds:.3f}",
                                     "status": status, "newton_iterations": iterations,
                                     "contact_seconds": contact, "diff": ""})
                    f.flush()
                    print(f"round {r + 1} {case:13} without {variant:20} {seconds:7.2f} s  {status} "
                          f"{iterations}", flush=True)
            # the round's differences to the run with every strategy (the outputs are deterministic)
            for case in cases:
                base = tmp / f"{case}-all" / "gamma3.csv"
                for variant in variants[1:]:
                    other = tmp / f"{case}-{variant}" / "gamma3.csv"
                    if base.exists() and other.exists():
                        d = difference(gamma3(base), gamma3(other))
                        writer.writerow({"round": r, "case": case, "variant": variant, "seconds": "",
                                         "status": "diff", "newton_iterations": "", "contact_seconds": "",
                                         "diff": f"{d:.2e}"})
            f.flush()


def total(iterations):
    """The run's Newton iterations: summary.json's list per step, summed."""
    try:
        value = json.loads(iterations)
    except ValueError:
        return iterations
    return sum(value) if isinstance(value, list) else value


def table(path):
    runs, diffs = {}, {}
    with open(path) as f:
        for row in csv.DictReader(f):
            key = (row["case"], row["variant"])
            if row["status"] == "diff":
                diffs[key] = max(diffs.get(key, 0.0), float(row["diff"]))
            else:
                runs.setdefault(key, []).append(row)
    cases = list(dict.fromkeys(k[0] for k in runs))
    variants = list(dict.fromkeys(k[1] for k in runs))
    print("| without | case | runs | median [s] | / all | Newton iterations | converged | gamma3 diff |")
    print("|---|---|---|---|---|---|---|---|")
    for variant in variants:
        for case in cases:
            rows = runs.get((case, variant))
            if not rows:
                continue
            base = [float(r["seconds"]) for r in runs.get((case, "all"), [])]
            seconds = [float(r["seconds"]) for r in rows]
            median = statistics.median(seconds)
            ratio = median / statistics.median(base) if base else float("nan")
            ok = all(r["status"] == "completed" for r in rows)
            iterations = sorted({str(total(r["newton_iterations"])) for r in rows})
            d = diffs.get((case, variant))
            print(f"| {variant} | {case} | {len(rows)} | {median:.2f} ({min(seconds):.2f}–{max(seconds):.2f}) | "
                  f"{ratio:.2f} | {'/'.join(iterations)} | {'yes' if ok else '**no**'} | "
                  f"{'' if d is None else f'{d:.1e}'} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("hvi", nargs="?")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--only", type=lambda s: s.split(","), default=None)
    ap.add_argument("--cases", type=lambda s: s.split(","), default=None)
    ap.add_argument("--csv", default="ablation.csv")
    ap.add_argument("--against", metavar="OLD_HVI", help="time another binary (variant `old`) against HVI")
    ap.add_argument("--table", metavar="CSV")
    args = ap.parse_args()
    if args.table:
        table(args.table)
        return 0
    if not args.hvi:
        ap.error("give the hvi binary (or --table CSV)")
    measure(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
