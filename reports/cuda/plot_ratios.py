#!/usr/bin/env python3
"""Chart of a cuda_ref report: every scene's new frame over the GPU's own OpenGL raster of the
same trace (hw_raster_ratio), per precision, at 1080p 1 spp and at 4K 4 spp, with issue 16's
lines (float <= 1.0x at 1080p and <= 0.5x at 4K 4 spp, exact <= 2.0x).

    python3 reports/cuda/plot_ratios.py reports/cuda/nvidia_h200.json [-o reports/cuda/nvidia_h200_ratios.png]

Reads the report's JSON (gpu_run.sh report) and writes a PNG (default: beside it,
<device>_ratios.png). Needs matplotlib (Debian: python3-matplotlib).
"""
import argparse
import json
import sys
from pathlib import Path

PRECISIONS = [("float", "float analytic", "#1f77b4"), ("exact", "exact analytic", "#ff7f0e"),
              ("hybrid_float", "float hybrid", "#9ecae1"), ("hybrid_exact", "exact hybrid", "#fdae6b")]
SETS = [("1080p", "1080p, 1 sample per pixel", 1.0), ("4k4", "4K, 4 samples per pixel", 0.5)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("report", type=Path, help="a cuda_ref report's JSON (reports/cuda/<device>.json)")
    ap.add_argument("-o", "--output", type=Path, help="the PNG to write (default: <report>_ratios.png)")
    a = ap.parse_args()
    try:
        report = json.loads(a.report.read_text())
        entries = report["entries"]
    except (OSError, ValueError, KeyError) as e:
        sys.exit(f"plot_ratios: {a.report}: not a cuda_ref report ({e})")
    ratio = {}
    budgets = sorted({e["pair_budget"] for e in entries if isinstance(e.get("pair_budget"), int)})
    for e in entries:
        r = e.get("hw_raster_ratio")
        if isinstance(r, (int, float)) and r > 0:
            ratio[(e.get("set", "1080p"), e["scene"], e["precision"])] = float(r)
    if not ratio:
        sys.exit(f"plot_ratios: {a.report}: no entry has a ratio to the GL raster (hw_raster_ratio)")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("plot_ratios: matplotlib is missing (Debian: python3-matplotlib)")

    out = a.output or a.report.with_name(a.report.stem + "_ratios.png")
    sets = [s for s in SETS if any(k[0] == s[0] for k in ratio)]
    fig, axes = plt.subplots(len(sets), 1, figsize=(13, 4.2 * len(sets)), squeeze=False)
    width = 0.8 / len(PRECISIONS)
    for ax, (set_name, title, float_line) in zip(axes[:, 0], sets):
        scenes = sorted({k[1] for k in ratio if k[0] == set_name})
        for i, (prec, label, color) in enumerate(PRECISIONS):
            xs = [j + (i - (len(PRECISIONS) - 1) / 2) * width for j in range(len(scenes))]
            ys = [ratio.get((set_name, s, prec), float("nan")) for s in scenes]
            if prec.startswith("hybrid") and budgets:
                label += f" (pair budget {', '.join(map(str, budgets))})"
            ax.bar(xs, ys, width, label=label, color=color)
        ax.axhline(float_line, color="#1f77b4", linestyle="--", linewidth=1, label=f"float's line ({float_line:g}x)")
        ax.axhline(2.0, color="#ff7f0e", linestyle="--", linewidth=1, label="exact's line (2x)")
        ax.legend(ncol=3, fontsize=8, loc="upper left")
        ax.set_yscale("log")
        ax.set_xticks(range(len(scenes)))
        ax.set_xticklabels(scenes, rotation=30, ha="right")
        ax.set_xlim(-0.6, len(scenes) - 0.4)
        ax.set_ylabel("new frame / GL raster (log)")
        ax.set_title(title)
        ax.grid(axis="y", which="both", alpha=0.3)
    smi = str(report.get("meta", {}).get("nvidia_smi", "")).split(",")
    driver = smi[1].strip() if len(smi) > 1 else "driver unknown"
    fig.suptitle(f"cuda_ref against the GPU's own OpenGL raster: {report.get('device', '?')}, {driver}, "
                 f"commit {str(report.get('commit', '?'))[:7]} (below 1: faster than GL)")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    print(f"plot_ratios: wrote {out} ({len(ratio)} ratios)")


if __name__ == "__main__":
    main()
