#!/usr/bin/env python3
"""Hybrid visibility against the exact z-buffer truth on every built-in scene (traces/scenes/*.json,
each at its own viewport): 1 and 4 samples, tiles 8, 32 and 128, and analytic beside it at 32x32.
Writes reports/hybrid/builtin_scenes.md. One run at a time, so that the times are comparable.

usage: reports/hybrid/run_builtin.py [--traces DIR] [--work DIR] [--scenes a,b,...] [--tilevis BIN]
"""
import argparse
import json
import pathlib
import platform
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
TILEVIS = ROOT / "build/model/app/tilevis"  # --tilevis: a copy, so that rebuilding meanwhile changes nothing
BUDGETS = {"hot_tile": [0, 20000], "teapot_stadium": [0, 20000]}  # scenes also run with a pair budget


def run(args):
    t0 = time.monotonic()
    p = subprocess.run([str(TILEVIS), *map(str, args)], capture_output=True, text=True,
                       env={"TILEVIS_PROGRESS": "0", "PATH": "/usr/bin:/bin"})
    if p.returncode != 0:
        sys.exit(f"failed: tilevis {' '.join(map(str, args))}\n{p.stderr}")
    return time.monotonic() - t0


def agreement(a, b):
    run(["compare", a, b])
    c = json.loads((pathlib.Path(a) / "compare.json").read_text())
    return c["samples_compared"], c["mismatched_samples"]


def main():
    global TILEVIS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--traces", default="/tmp/tilevis_hybrid/traces")
    ap.add_argument("--work", default="/tmp/tilevis_hybrid/runs")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--tilevis", default=str(TILEVIS))
    a = ap.parse_args()
    TILEVIS = pathlib.Path(a.tilevis)
    traces, work = pathlib.Path(a.traces), pathlib.Path(a.work)
    traces.mkdir(parents=True, exist_ok=True)
    scenes = a.scenes.split(",") if a.scenes else sorted(p.stem for p in (ROOT / "traces/scenes").glob("*.json"))
    rows, bad, runs = [], 0, 0
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"], capture_output=True,
                           text=True).stdout.strip()
    for sc in scenes:
        tvt = traces / f"{sc}.tvt"
        if not tvt.exists():
            run(["trace", ROOT / "traces/scenes" / f"{sc}.json", "-o", tvt])
        for spp in (1, 4):
            base = work / sc / f"s{spp}"
            truth = base / "truth"
            run(["golden", tvt, "--samples", spp, "--truth", "-o", truth])
            points = [("hybrid", t, b) for t in (8, 32, 128) for b in BUDGETS.get(sc, [0])] + [("analytic", 32, 0)]
            for mode, tile, budget in points:
                out = base / f"{mode}{tile}b{budget}"
                secs = run(["golden", tvt, "--samples", spp, "--tile", tile, "--mode", mode, "--pair-budget", budget,
                            "-o", out])
                compared, mismatched = agreement(out, truth)
                st = json.loads((out / "stats.json").read_text())
                tot, fb = st["totals"], st["totals"].get("per_pixel_fallback", {})
                ntiles = sum(1 for _ in open(out / "tiles.csv")) - 1
                if mode == "hybrid":
                    runs += 1
                    bad += mismatched != 0
                rows.append([sc, spp, tile, mode + (f" (budget {budget})" if budget else ""),
                             f"{100 * (1 - mismatched / compared):.6f} %" if compared else "–",
                             f"{mismatched} / {compared}", fb.get("tiles", "–"), ntiles,
                             fb.get("tiles_interpenetration", "–"), fb.get("tiles_non_opaque", "–"),
                             fb.get("tiles_budget", "–"), fb.get("samples", "–"),
                             fb.get("triangles", "–"), fb.get("triangles_crossing", "–"),
                             tot["triangles_front"], f"{secs:.2f}"])
                print(" | ".join(map(str, rows[-1])), flush=True)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    md = ["# Hybrid visibility against the exact z-buffer truth, built-in scenes", "",
          "`tilevis golden T --mode hybrid` against `tilevis golden T --truth` (`tilevis compare`), every scene of "
          "`traces/scenes` at its own viewport, 1 and 4 samples, tiles 8, 32 and 128 (`hot_tile` and "
          "`teapot_stadium` also with `--pair-budget 20000`), and `--mode analytic` at 32x32 beside them. "
          f"Made by `reports/hybrid/run_builtin.py` on {platform.node()} ({cpu}, {platform.system()}), commit "
          f"{commit}{' with uncommitted changes' if dirty else ''}, one run at a time; `s` is the wall time of the "
          "golden run (setup, binning, tiles, writing the outputs).", "",
          f"Hybrid: {runs} runs, {runs - bad} with 0 differing samples.", "",
          "Columns: tiles per pixel (and why: interpenetration, non-opaque content, pair budget), the samples "
          "those tiles cover, the triangles binned to them and, in interpenetration tiles, how many of those "
          "cross another triangle (what a fallback of triangle granularity would send per pixel).", "",
          "| scene | spp | tile | mode | agreement | differing / covered | tiles per pixel | of tiles | "
          "interpenetration | non-opaque | budget | samples per pixel | triangles in them | crossing | "
          "front triangles | s |",
          "|" + "---|" * 16]
    md += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    (ROOT / "reports/hybrid/builtin_scenes.md").write_text("\n".join(md) + "\n")
    print(f"hybrid: {runs - bad} of {runs} runs equal the truth; wrote reports/hybrid/builtin_scenes.md")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
