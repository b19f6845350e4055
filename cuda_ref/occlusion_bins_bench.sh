#!/usr/bin/env bash
# On the GPU machine, after `cuda_ref/gpu_run.sh build`: the CUDA reference with finer
# occlusion bins (SVGPU §4.1) against one bin per tile, on a few scenes at 32x32 tiles, both
# precisions. Prints a Markdown table (total and occlusion-stage GPU time; agreement of each
# binned run with the unbinned one, which must be 100 % with 0 tile cells differing).
#
#   bash cuda_ref/occlusion_bins_bench.sh [SCENE...]      (default: bunny dragon_bunnies million stack armadillo_box)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export LD_LIBRARY_PATH="/tmp/sysroot/usr/lib/x86_64-linux-gnu:/tmp/sysroot/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
BIN=build-gpu/model/app/tilevis
TRACES=build-gpu/gpu_traces
WORK=$(mktemp -d)
[ -x "$BIN" ] || { echo "occlusion_bins_bench: $BIN missing (run cuda_ref/gpu_run.sh build)" >&2; exit 1; }
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(bunny dragon_bunnies million stack armadillo_box)
echo "| scene | precision | occlusion bin | total ms | occlusion ms | vs one bin per tile |"
echo "|---|---|---|---|---|---|"
for s in "${scenes[@]}"; do
  for p in exact float; do
    for b in 32 8 4; do
      "$BIN" cuda "$TRACES/$s.tvt" --tile 32 --precision "$p" --occlusion-bin "$b" -o "$WORK/$s-$p-$b" >/dev/null
      [ "$b" = 32 ] || "$BIN" compare "$WORK/$s-$p-$b" "$WORK/$s-$p-32" >/dev/null
      python3 - "$WORK/$s-$p-$b" "$s" "$p" "$b" <<'PY'
import json, os, sys
d, s, p, b = sys.argv[1:]
st = json.load(open(os.path.join(d, "stats.json")))
sm = st["stage_ms"]
occ = sm["occlusion"] if isinstance(sm, dict) else next(x["ms"] for x in sm if x["name"] == "occlusion")
c = os.path.join(d, "compare.json")
vs = "(reference)"
if os.path.exists(c):
    cj = json.load(open(c))
    vs = f"{100 * cj['sample_agreement']:.4f} %, {cj['tile_counter_mismatches']} tile cells differ"
print(f"| {s} | {p} | {b}x{b} | {st['total_ms']:.3f} | {occ:.3f} | {vs} |")
PY
    done
  done
done
rm -rf "$WORK"
