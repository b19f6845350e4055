#!/usr/bin/env python3
"""Timing error of the SystemC EVU's cost functions *before calibration* (838c783) against the
RTL, per tile job and per frame: reports/rtl's before-calibration tables. The calibrated cost
functions are compared with the RTL on whole frames by rtl_ref/tools/calibrated_error.py.

Reads the per-tile CSVs the testbenches write with --csv (tb_tile_sequencer, tb_clip,
tb_occlude over the dumped tile jobs) and prints a Markdown report: for each sub-unit and
scene, the frame's cycles (RTL, model), the frame error |model - rtl| / rtl, and the per-tile
error's mean and percentiles over tiles where the RTL does any work.

  rtl_ref/tools/calibration.py REJECT.csv CLIP.csv OCCLUDE.csv
"""
import csv
import statistics
import sys
from collections import defaultdict


def load(path, rtl, model):
    rows = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            scene = r["source"].split("/")[-2]
            rows[scene].append((rtl(r), int(r[model]), r))
    return rows


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * (len(xs) - 1) + 0.5))]


def table(title, rows, note):
    print(f"### {title}\n\n{note}\n")
    print("| scene | tile jobs | RTL cycles | model cycles | frame error | per-tile mean error | median | p90 | max |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene, rs in sorted(rows.items()):
        rtl = sum(r for r, _, _ in rs)
        model = sum(m for _, m, _ in rs)
        errs = [abs(m - r) / r for r, m, _ in rs if r > 0]
        print(f"| {scene} | {len(rs)} | {rtl:,} | {model:,} | {abs(model - rtl) / rtl:.1%} | "
              f"{statistics.mean(errs):.1%} | {pct(errs, 0.5):.1%} | {pct(errs, 0.9):.1%} | {max(errs):.1%} |")
    print()


def main():
    reject, clip, occlude = sys.argv[1:4]
    # Reject: the sequencer's walk (issue clocks + 1 to end the pass) plus PairReject's 3-clock
    # pipeline, against EvuReject::cost at 8 lanes, ii 1, latency 6. List loading (tile fetch's
    # writes into the on-chip lists) is the tile fetch unit's time in the model, so left out.
    table("Reject (TileSequencer x8 + PairReject)",
          load(reject, lambda r: int(r["rtl_walk_cycles"]) + 3, "model_reject_cycles"),
          "RTL: TileSequencer walk + PairReject latency (3); model: EvuReject::cost, 8 lanes, ii 1, latency 6.")
    table("Clip (one lane)", load(clip, lambda r: int(r["rtl_clocks"]), "model_cycles"),
          "RTL: Clip clocks per split, 2n + 2 for a parent of n edges; model: EvuClip::cost at 1 lane, "
          "ii 4, latency 12, charged per candidate and per split.")
    table("Occlude (one lane)", load(occlude, lambda r: int(r["rtl_clocks"]), "model_cycles"),
          "RTL: per piece 2 clocks for the interior point, one per occluder test, 1 more for the last verdict; "
          "model: EvuOcclude::cost at 1 lane, ii 1, latency 10, charged per piece and per test.")


if __name__ == "__main__":
    main()
