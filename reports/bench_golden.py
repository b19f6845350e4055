#!/usr/bin/env python3
"""Golden pipeline benchmark and accuracy run: every scene x tile size x sample count,
golden against the exact z-buffer truth. Prints a table; writes OUT/golden.{md,json}.

  python3 reports/bench_golden.py --bin build/model/app/tilevis --out reports/golden
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path


def run_measured(cmd):
    t0 = time.time()
    p = subprocess.Popen([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(p.pid, 0)
    out = p.stdout.read().decode()
    err = p.stderr.read().decode()
    if status != 0:
        sys.stderr.write(out + err)
        raise SystemExit(f"bench: failed: {' '.join(map(str, cmd))}")
    return out, time.time() - t0, usage.ru_maxrss / 1024, usage.ru_utime + usage.ru_stime


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--scenes", default="traces/scenes")
    ap.add_argument("--out", required=True)
    ap.add_argument("--tiles", default="16,32,64")
    ap.add_argument("--samples", default="1,4")
    ap.add_argument("--only", default="", help="comma-separated scene names")
    a = ap.parse_args()
    out = Path(a.out)
    work = out / "work"
    (work / "traces").mkdir(parents=True, exist_ok=True)
    scenes = sorted(Path(a.scenes).glob("*.json"))
    if a.only:
        scenes = [s for s in scenes if s.stem in a.only.split(",")]
    rows = []
    for scene in scenes:
        trace = work / "traces" / f"{scene.stem}.tvt"
        run_measured([a.bin, "trace", scene, "-q", "-o", trace])
        for samples in a.samples.split(","):
            tdir = work / f"{scene.stem}_s{samples}_truth"
            _, truth_s, truth_mb, _ = run_measured([a.bin, "golden", trace, "--truth", "--samples", samples, "-o", tdir])
            for tile in a.tiles.split(","):
                gdir = work / f"{scene.stem}_s{samples}_t{tile}"
                _, wall, mb, cpu = run_measured([a.bin, "golden", trace, "--tile", tile, "--samples", samples, "-o", gdir])
                run_measured([a.bin, "compare", gdir, tdir])
                c = json.loads((gdir / "compare.json").read_text())
                if c["mismatched_samples"]:
                    run_measured([a.bin, "compare", gdir, tdir, "--explain", trace])
                    c = json.loads((gdir / "compare.json").read_text())
                g = json.loads((gdir / "stats.json").read_text())
                r = {"scene": scene.stem, "tile": tile, "samples": int(samples),
                     "golden_seconds": g["host_seconds"], "golden_wall": wall, "golden_cpu": cpu, "golden_peak_mib": mb,
                     "truth_seconds": truth_s, "truth_peak_mib": truth_mb,
                     "sample_agreement": c["sample_agreement"], "mismatched_samples": c["mismatched_samples"],
                     "samples_compared": c["samples_compared"], "mismatch_causes": c.get("mismatch_causes", {}), **{k: g["totals"][k] for k in (
                         "triangles_in", "silhouette_edges", "candidate_pairs", "clip_polygons", "pieces",
                         "visible_pieces")}}
                rows.append(r)
                print(f"{r['scene']:<16} tile {tile:>7} s{samples}  golden {r['golden_seconds']:7.3f} s "
                      f"{mb:7.1f} MiB  agreement {100 * r['sample_agreement']:9.5f} % "
                      f"({r['mismatched_samples']} of {r['samples_compared']})  pieces {r['pieces']}", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")),
               platform.machine())
    machine = f"{platform.node()}: {cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"
    lines = ["# Golden pipeline: time, memory and agreement with the exact z-buffer truth", "",
             f"Machine: {machine}. Commit: {commit}. Command: `python3 reports/bench_golden.py --bin build/model/app/tilevis "
             f"--out {a.out} --tiles {a.tiles} --samples {a.samples}`. Golden time is the pipeline's own "
             "(setup + tiles, single-threaded), CPU s the whole process's user + system time (trace read and output writing included), "
             "peak memory the whole process's.", "",
             "| scene | tile | spp | golden s | process CPU s | peak MiB | truth s | agreement | mismatched | causes | pieces | visible |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['tile']} | {r['samples']} | {r['golden_seconds']:.3f} | {r['golden_cpu']:.2f} | {r['golden_peak_mib']:.0f} | "
                     f"{r['truth_seconds']:.2f} | {100 * r['sample_agreement']:.5f} % | {r['mismatched_samples']} | "
                     f"{'; '.join(f'{n} {k}' for k, n in r['mismatch_causes'].items())} | {r['pieces']:,} | {r['visible_pieces']:,} |")
    # SVGPU Fig. 6: output triangles of the bunny against the number of bins (64 .. 4,096
    # bins over the 1920x1080 screen: 8x8 .. 64x64 tiles).
    fig6 = []
    bunny = work / "traces" / "bunny.tvt"
    if bunny.exists():
        paper = {"240x135": "32K", "120x68": "37K", "60x34": "48K", "30x17": "71K"}
        lines += ["", "## Output growth: bunny, SVGPU Fig. 6", "",
                  "| bins | tile | pieces | visible pieces | visible output triangles | SVGPU Fig. 6 |", "|---|---|---|---|---|---|"]
        for bins, tile in ((64, "240x135"), (256, "120x68"), (1024, "60x34"), (4096, "30x17")):
            gdir = work / f"bunny_fig6_{tile}"
            run_measured([a.bin, "golden", bunny, "--tile", tile, "-o", gdir])
            t = json.loads((gdir / "stats.json").read_text())["totals"]
            fig6.append({"bins": bins, "tile": tile, "pieces": t["pieces"], "visible_pieces": t["visible_pieces"],
                         "visible_triangles": t["visible_triangles"]})
            lines.append(f"| {bins:,} | {tile} | {t['pieces']:,} | {t['visible_pieces']:,} | {t['visible_triangles']:,} | {paper[tile]} |")
    (out / "golden.md").write_text("\n".join(lines) + "\n")
    (out / "golden.json").write_text(json.dumps({"machine": machine, "commit": commit, "rows": rows, "fig6": fig6}, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
