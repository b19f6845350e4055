#!/usr/bin/env python3
"""The calibrated EVU cost functions against the RTL, per tile and per frame, on whole frames.

Reads pairs of `tilevis sim` result directories of the same trace, one at fidelity `primitive`
(the model's cost functions: model/units/early_visibility_unit) and one at fidelity `rtl` (the
same tiles with the EVU's clocks from its Verilated RTL), and prints a Markdown report: per scene
and EVU sub-unit (tiles.csv's cycles_evu_reject, cycles_evu_clip, cycles_evu_occlude), the
frame's cycles at rtl, the frame error |model - rtl| / rtl and the per-tile error's mean and
largest over the tiles where the RTL does any work; then each scene's frame cycles.

  rtl_ref/tools/calibrated_error.py DIR   # DIR holds <scene>_primitive/ and <scene>_rtl/
                                          # (reports/bench_sim.py's work folder)
"""
import csv
import json
import sys
from pathlib import Path

UNITS = ("cycles_evu_reject", "cycles_evu_clip", "cycles_evu_occlude")


def tiles(d):
    with open(d / "tiles.csv") as f:
        return list(csv.DictReader(f))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = Path(sys.argv[1])
    scenes = sorted(p.name[: -len("_rtl")] for p in root.glob("*_rtl") if (p / "stats.json").exists())
    scenes = [s for s in scenes if (root / f"{s}_primitive" / "stats.json").exists()]
    if not scenes:
        sys.exit(f"calibrated_error: no <scene>_primitive and <scene>_rtl result pairs in {root}")
    print("| scene | sub-unit | tiles with RTL work | RTL cycles | model cycles | frame error | "
          "per-tile mean error | largest |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    frames = []
    worst = 0.0
    for s in scenes:
        prim, rtl = root / f"{s}_primitive", root / f"{s}_rtl"
        sp, sr = (json.loads((d / "stats.json").read_text()) for d in (prim, rtl))
        if sp["fidelity"] != "primitive" or sr["fidelity"] != "rtl" or sp["trace_fnv1a64"] != sr["trace_fnv1a64"]:
            sys.exit(f"calibrated_error: {s}: not a primitive and an rtl run of one trace")
        tp, tr = tiles(prim), tiles(rtl)
        if [(a["tx"], a["ty"]) for a in tp] != [(b["tx"], b["ty"]) for b in tr]:
            sys.exit(f"calibrated_error: {s}: different tile grids")
        for u in UNITS:
            m = [int(a[u]) for a in tp]
            r = [int(b[u]) for b in tr]
            errs = [abs(x - y) / y for x, y in zip(m, r) if y > 0]
            if not errs:
                continue
            fe = abs(sum(m) - sum(r)) / sum(r)
            worst = max(worst, fe, max(errs))
            print(f"| {s} | {u[len('cycles_evu_'):]} | {len(errs):,} | {sum(r):,} | {sum(m):,} | {fe:.2%} | "
                  f"{sum(errs) / len(errs):.2%} | {max(errs):.2%} |")
        frames.append((s, sr["totals"]["cycles"], sp["totals"]["cycles"]))
    print()
    print("| scene | frame cycles, rtl | frame cycles, primitive | error |")
    print("|---|---:|---:|---:|")
    for s, r, m in frames:
        print(f"| {s} | {r:,} | {m:,} | {abs(m - r) / r:.2%} |")
    print()
    print(f"Largest error, per frame or per tile, over {len(scenes)} scenes: {worst:.2%}.")


if __name__ == "__main__":
    main()
