"""Whole-process wall time of `hvi solve` against the numpy/scipy reference (benches/numpy_reference.py)
on the paper's example, interleaved, and a check that both give the same final displacement.

    python3 benches/whole_run_vs_numpy.py HVI_BINARY [NX NY STEPS] [--repeats R]

Defaults 256 128 128 (h = k = 1/128), R = 3. Prints each wall time, the medians, the ratio
numpy/hvi and max |u_hvi - u_numpy| / max |u_hvi| at t = T. Needs numpy and scipy only.
"""
import argparse
import base64
import json
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
except ImportError as e:  # pragma: no cover
    raise SystemExit(f"whole_run_vs_numpy.py needs numpy and scipy ({e}): pip install numpy scipy")

HERE = pathlib.Path(__file__).resolve().parent


def vtu_array(path, name):
    """A Float64 point array of an uncompressed .vtu written by hvi (UInt64 header, little-endian):
    raw appended binary (current hvi) or inline base64 (hvi before the raw layout)."""
    raw = pathlib.Path(path).read_bytes()
    at = raw.find(b"<AppendedData")
    if at < 0:
        return vtu_array_base64(path, raw.decode(), name)
    head = raw[:at].decode()
    if "compressor" in head[:300] or 'encoding="raw"' not in raw[at:at + 100].decode(errors="replace"):
        raise SystemExit(f"{path}: appended data that is compressed or not raw")
    data = raw.index(b"_", at) + 1  # the appended block starts after the '_'
    for attrs in re.findall(r"<DataArray([^>]*)>", head):
        if f'Name="{name}"' in attrs and 'type="Float64"' in attrs:
            start = data + int(re.search(r'offset="(\d+)"', attrs).group(1))
            n = int(np.frombuffer(raw, "<u8", 1, start)[0])
            comps = re.search(r'NumberOfComponents="(\d+)"', attrs)
            values = np.frombuffer(raw, "<f8", n // 8, start + 8)
            return values.reshape(-1, int(comps.group(1)) if comps else 1)
    raise SystemExit(f"{path}: no Float64 array {name}")


def vtu_array_base64(path, text, name):
    """A Float64 point array of an uncompressed base64 .vtu (hvi's earlier layout)."""
    for attrs, data in re.findall(r"<DataArray([^>]*)>([^<]*)<", text):
        if f'Name="{name}"' in attrs and 'type="Float64"' in attrs and "compressor" not in text[:300]:
            raw = base64.b64decode(data.strip())
            n = int(np.frombuffer(raw[:8], "<u8")[0])
            comps = re.search(r'NumberOfComponents="(\d+)"', attrs)
            return np.frombuffer(raw[8:8 + n], "<f8").reshape(-1, int(comps.group(1)) if comps else 1)
    raise SystemExit(f"{path}: no uncompressed Float64 array {name}")


def hvi_final(out_dir):
    """Final-frame displacement (nodes x 2) and the Newton iterations of an hvi run."""
    frames = sorted(pathlib.Path(out_dir).glob("solution_*.vtu"))
    summary = json.loads((pathlib.Path(out_dir) / "summary.json").read_text())
    return vtu_array(frames[-1], "displacement")[:, :2], summary["newton_iterations"]


def timed(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("hvi")
    ap.add_argument("sizes", nargs="*", type=int, default=[256, 128, 128], help="NX NY STEPS")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    nx, ny, steps = args.sizes
    with tempfile.TemporaryDirectory(prefix="hvi-vs-numpy-") as tmp:
        return compare(args, nx, ny, steps, pathlib.Path(tmp))


def compare(args, nx, ny, steps, tmp):
    hvi_cmd = [args.hvi, "solve", f"rect:{nx}x{ny}", "--set", f"time.steps={steps}",
               "--set", f"output.every={steps}", "--out", str(tmp / "hvi"), "--quiet"]
    np_cmd = [sys.executable, str(HERE / "numpy_reference.py"), "--nx", str(nx), "--ny", str(ny),
              "--steps", str(steps), "--out", str(tmp / "numpy.npz")]
    t_hvi, t_np = [], []
    for i in range(args.repeats):
        t_np.append(timed(np_cmd))
        t_hvi.append(timed(hvi_cmd))
        print(f"run {i + 1}: numpy {t_np[-1]:.3f} s, hvi {t_hvi[-1]:.3f} s", flush=True)
    m_np, m_hvi = statistics.median(t_np), statistics.median(t_hvi)
    print(f"median: numpy {m_np:.3f} s, hvi {m_hvi:.3f} s, ratio numpy/hvi {m_np / m_hvi:.2f}")
    u_hvi, it_hvi = hvi_final(tmp / "hvi")
    ref = np.load(tmp / "numpy.npz")
    diff = np.abs(u_hvi - ref["u"]).max() / np.abs(u_hvi).max()
    print(f"final displacement: max|u_hvi - u_numpy| / max|u_hvi| = {diff:.2e}; Newton iterations "
          f"hvi {sum(it_hvi)}, numpy {int(ref['newton'].sum())}")
    return 0 if diff < 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main())
