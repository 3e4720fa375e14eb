#!/usr/bin/env bash
# Size and write time of the .vtu/.vtp series by output.compress, measured side by side:
# runs of `hvi solve rect:256x128` (the paper's scene at h = 1/128: 33 153 nodes, 32 768 quads)
# with 8 steps, raw / level 1 / level 6 interleaved, REPS rounds; prints per setting the median
# output phase (summary.json phases.output: stresses excluded) and the bytes of the .vtu/.vtp
# files per frame.  Usage: benches/output_compression.sh [REPS] (default 3; needs a release build)
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-3}
hvi=target/release/hvi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
declare -A times sizes
for r in $(seq "$reps"); do
  for c in false 1 6; do
    out="$tmp/$c-$r"
    "$hvi" solve rect:256x128 --out "$out" --quiet --set time.steps=8 --set output.compress=$c >/dev/null
    t=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['phases']['output'])" "$out/summary.json")
    s=$(cat "$out"/*.vtu "$out"/*.vtp | wc -c)
    times[$c]+="$t "
    sizes[$c]=$s
    rm -rf "$out"
  done
done
for c in false 1 6; do
  python3 - "$c" "${sizes[$c]}" ${times[$c]} <<'PY'
import statistics, sys
c, size, ts = sys.argv[1], int(sys.argv[2]), [float(t) for t in sys.argv[3:]]
print(f"compress={c:5}  output phase median {statistics.median(ts):.3f} s over {len(ts)} runs {ts}  {size/9/1e6:.2f} MB per frame (.vtu + .vtp)")
PY
done
