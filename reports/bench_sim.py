#!/usr/bin/env python3
"""Host time of the SystemC tiler model per fidelity level per scene (a benchmark, not a
timed test). Prints a table and writes OUT/sim_bench.{md,json}.

  python3 reports/bench_sim.py --bin build/model/app/tilevis --out reports/sim_bench

Beside each level's host time it gives the frame cycles and their deviation from the
primitive level (the most detailed one the model has; the RTL level will replace it as
the reference), so that speed is never quoted without its accuracy. Targets (issue 4):
bunny 1920x1080 at fidelity tile <= 5 s wall, million <= 60 s, on a 2-core machine.
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

LEVELS = ("analytic", "tile", "primitive")
TARGETS = {("bunny", "tile"): 5.0, ("million", "tile"): 60.0}


def run_measured(cmd):
    t0 = time.time()
    p = subprocess.Popen([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = p.communicate()
    wall = time.time() - t0
    if p.returncode != 0:
        sys.stderr.write(out.decode() + err.decode())
        raise SystemExit(f"bench_sim: failed: {' '.join(map(str, cmd))}")
    return wall


def cpu_name():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", required=True)
    ap.add_argument("--scenes", default="traces/scenes")
    ap.add_argument("--out", required=True)
    ap.add_argument("--only", default="", help="comma-separated scene names")
    ap.add_argument("--mode", default="analytic", help="visibility mode (sim.mode)")
    ap.add_argument("--tile", default="32")
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
        if not trace.exists():
            run_measured([a.bin, "trace", scene, "-q", "-o", trace])
        per = {}
        for level in LEVELS:
            d = work / f"{scene.stem}_{level}"
            wall = run_measured([a.bin, "sim", trace, "--tile", a.tile, "-p", f"sim.fidelity={level}",
                                 "-p", f"sim.mode={a.mode}", "-o", d])
            s = json.loads((d / "stats.json").read_text())
            per[level] = {"wall_seconds": wall, "host_seconds": s["host_seconds"], "cycles": s["totals"]["cycles"],
                          "triangles": s["totals"]["triangles_in"], "tiles": s["totals"]["tiles_rendered"]}
        ref = per["primitive"]["cycles"]
        for level in LEVELS:
            r = {"scene": scene.stem, "level": level, **per[level],
                 "cycles_vs_primitive": abs(per[level]["cycles"] - ref) / ref if ref else 0.0}
            target = TARGETS.get((scene.stem, level))
            r["target_seconds"] = target
            r["meets_target"] = None if target is None else r["wall_seconds"] <= target
            rows.append(r)
            mark = "" if target is None else (f"  (target <= {target:g} s: {'met' if r['meets_target'] else 'MISSED'})")
            print(f"{scene.stem:<16} {level:<9} wall {r['wall_seconds']:7.2f} s  model {r['host_seconds']:7.2f} s  "
                  f"{r['cycles']:>12,} cycles  {100 * r['cycles_vs_primitive']:6.2f} % from primitive{mark}", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    machine = f"{platform.node()}, {os.cpu_count()} cores, {cpu_name()}"
    lines = ["# SystemC tiler model: host time per fidelity level", "",
             f"Machine: {machine}. Commit: {commit}. Command: `python3 reports/bench_sim.py --bin {a.bin} --out {a.out}"
             f" --mode {a.mode} --tile {a.tile}`. Wall = the whole `tilevis sim` process (trace read, setup, "
             "functional work, simulation, outputs); model = elaboration to results. Cycles are the frame's; "
             "'from primitive' is their deviation from the primitive level's.", "",
             "| scene | triangles | level | wall s | model s | frame cycles | from primitive |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['level']} | {r['wall_seconds']:.2f} | "
                     f"{r['host_seconds']:.2f} | {r['cycles']:,} | {100 * r['cycles_vs_primitive']:.2f} % |")
    (out / "sim_bench.md").write_text("\n".join(lines) + "\n")
    (out / "sim_bench.json").write_text(json.dumps({"machine": machine, "commit": commit, "rows": rows}, indent=2))
    print(f"wrote {out / 'sim_bench.md'}")


if __name__ == "__main__":
    main()
