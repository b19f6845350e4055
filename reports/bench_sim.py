#!/usr/bin/env python3
"""Host time of the SystemC tiler model per fidelity level per scene (a benchmark, not a
timed test). Prints a table and writes OUT/sim_bench.{md,json}.

  python3 reports/bench_sim.py --bin build/model/app/tilevis --out reports/sim_bench

Beside each level's host time it gives the frame cycles and their deviation from the
reference level, rtl (the EVU's clocks from its Verilated RTL; primitive where the build has
no Verilator, and the table says so), so that speed is never quoted without its accuracy;
auto's rows add its confidence interval and the share of tiles it simulated, and auto runs
again on seeds 2..N (--auto-seeds, default 8) to say how often its interval holds. A chart of
host time against error per scene goes to OUT/sim_bench.png. Targets (issue 4): bunny
1920x1080 at fidelity tile <= 5 s wall, million <= 60 s, on a 2-core machine.

Level "tile (replayed)" is fidelity tile replaying a recorded functional pass
(sim.functional_record, issue 15): a recording run at fidelity tile (not measured) writes
OUT/work/SCENE.rec, then the measured run replays it (setup, binning and visibility not
computed; the same cycles and outputs). Its rows add the record's size and load seconds.
Level "tile (detailed memory)" is fidelity tile with memory.model=detailed: the DRAM controller
and DRAM model that fidelity primitive uses, where tile's own default is the bandwidth model.
"""
import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

LEVELS = ("analytic", "tile", "tile (replayed)", "tile (detailed memory)", "primitive", "auto", "rtl")
REPLAYED = "tile (replayed)"  # fidelity tile replaying the record a recording run wrote
DETAILED = "tile (detailed memory)"  # fidelity tile with the DRAM controller and DRAM model (memory.model=detailed)


def level_args(level):
    """The fidelity a level runs at, the folder name part it writes to, and its further parameters."""
    if level == REPLAYED:
        return "tile", "tile_replayed", []
    if level == DETAILED:
        return "tile", "tile_detailed_memory", ["-p", "memory.model=detailed"]
    return level, level, []
TARGETS = {("bunny", "tile"): 5.0, ("million", "tile"): 60.0}


def run_measured(cmd, allow_fail=False):
    t0 = time.time()
    p = subprocess.Popen([str(c) for c in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = p.communicate()
    wall = time.time() - t0
    if p.returncode != 0:
        if allow_fail:
            return (out.decode() + err.decode()).strip().splitlines()[-1:] or ["failed"]
        sys.stderr.write(out.decode() + err.decode())
        raise SystemExit(f"bench_sim: failed: {' '.join(map(str, cmd))}")
    return wall


def chart(rows, reference, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("bench_sim: no matplotlib, no chart", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(8, 5))
    markers = {"analytic": "o", "tile": "s", REPLAYED: "P", DETAILED: "x", "primitive": "^", "auto": "*", "rtl": "D"}
    for level in LEVELS:
        pts = [(r["host_seconds"], max(100 * r["cycles_vs_reference"], 1e-3)) for r in rows if r["level"] == level]
        if pts:
            ax.scatter(*zip(*pts), marker=markers[level], s=60 if level == "auto" else 30, label=level)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("host seconds (model: elaboration to results)")
    ax.set_ylabel(f"|frame cycles - {reference}| / {reference}, %  (0 drawn at 0.001)")
    ax.set_title(f"speed against accuracy, every built-in scene, reference {reference}")
    ax.axhline(2.0, color="grey", lw=0.8, ls="--")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


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
    ap.add_argument("--auto-seeds", type=int, default=8,
                    help="fidelity auto on seeds 1..N (the tables show seed 1): how often its interval holds")
    a = ap.parse_args()
    out = Path(a.out)
    work = out / "work"
    (work / "traces").mkdir(parents=True, exist_ok=True)
    scenes = sorted(Path(a.scenes).glob("*.json"))
    if a.only:
        scenes = [s for s in scenes if s.stem in a.only.split(",")]
    rows = []
    seeds = []
    failures = {}
    for scene in scenes:
        trace = work / "traces" / f"{scene.stem}.tvt"
        if not trace.exists():
            run_measured([a.bin, "trace", scene, "-q", "-o", trace])
        per = {}
        for level in LEVELS:
            fidelity, folder, extra = level_args(level)
            d = work / f"{scene.stem}_{folder}"
            if level == REPLAYED:
                record = work / f"{scene.stem}.rec"
                record.unlink(missing_ok=True)
                extra = extra + ["-p", f"sim.functional_record={record}"]
                run_measured([a.bin, "sim", trace, "--tile", a.tile, "-p", "sim.fidelity=tile", "-p", f"sim.mode={a.mode}",
                              *extra, "-o", work / f"{scene.stem}_tile_recording"])
            wall = run_measured([a.bin, "sim", trace, "--tile", a.tile, "-p", f"sim.fidelity={fidelity}",
                                 "-p", f"sim.mode={a.mode}", *extra, "-o", d], allow_fail=level == "rtl")
            if isinstance(wall, list):  # rtl failed: unavailable in this build, or the RTL refused a job
                print(f"{scene.stem}: fidelity rtl failed: {wall[0]}", file=sys.stderr)
                failures[scene.stem] = wall[0]
                continue
            s = json.loads((d / "stats.json").read_text())
            # The model's seconds split: the functional model's (setup, binning, visibility,
            # results: the same work at every level) and the rest, the timing model's (SystemC,
            # the units, the memory system; the Verilated EVU at rtl).
            functional = s.get("host_functional_seconds")
            per[level] = {"wall_seconds": wall, "host_seconds": s["host_seconds"],
                          "prepare_seconds": s.get("host_prepare_seconds"), "functional_seconds": functional,
                          "timing_seconds": None if functional is None else s["host_seconds"] - functional,
                          "rtl_seconds": s.get("host_rtl_seconds"), "cycles": s["totals"]["cycles"],
                          "triangles": s["totals"]["triangles_in"], "tiles": s["totals"]["tiles_rendered"],
                          "geometry_end_cycles": s["totals"].get("geometry_end_cycles")}
            if level == REPLAYED:
                if s.get("functional") != "replayed":
                    raise SystemExit(f"bench_sim: {d}: expected a replayed functional pass, got {s.get('functional')}")
                per[level].update({"record_bytes": record.stat().st_size,
                                   "record_load_seconds": s["host_functional_record_seconds"]})
            if s.get("sampling"):
                m = s["sampling"]
                per[level].update({"interval": m["interval_cycles"], "tiles_total": m["tiles"],
                                   "tiles_simulated": m["tiles_simulated"], "within_budget": m["within_budget"]})
                if m.get("geometry"):
                    per[level].update({"geometry_triangles_simulated": m["geometry"]["triangles_simulated"],
                                       "geometry_estimate": m["geometry"]["estimated_cycles"]})
        reference = "rtl" if "rtl" in per else "primitive"
        ref = per[reference]["cycles"]
        # auto's other seeds: its error and whether its interval holds the reference, per seed.
        for seed in range(1, a.auto_seeds + 1):
            if seed == 1:
                s = per["auto"]
                wall, host, cycles, interval = s["wall_seconds"], s["host_seconds"], s["cycles"], s["interval"]
                geometry = s.get("geometry_estimate")
            else:
                d = work / f"{scene.stem}_auto_seed{seed}"
                wall = run_measured([a.bin, "sim", trace, "--tile", a.tile, "-p", "sim.fidelity=auto", "-p",
                                     f"sim.sample_seed={seed}", "-p", f"sim.mode={a.mode}", "-o", d])
                st = json.loads((d / "stats.json").read_text())
                host, cycles, interval = st["host_seconds"], st["totals"]["cycles"], st["sampling"]["interval_cycles"]
                geometry = (st["sampling"].get("geometry") or {}).get("estimated_cycles")
                shutil.rmtree(d)
            # The sampled geometry against the reference's (where its one segment reached the
            # parameter buffer).
            ref_geometry = (per[reference].get("geometry_end_cycles") or [None])[0]
            seeds.append({"scene": scene.stem, "seed": seed, "wall_seconds": wall, "host_seconds": host,
                          "cycles": cycles, "interval": interval, "reference": reference,
                          "error": (cycles - ref) / ref if ref else 0.0,
                          "geometry_error": (geometry - ref_geometry) / ref_geometry
                          if geometry is not None and ref_geometry else None,
                          "holds": interval[0] <= ref <= interval[1]})
        for level in LEVELS:
            if level not in per:
                continue
            r = {"scene": scene.stem, "level": level, "reference": reference, **per[level],
                 "cycles_vs_reference": abs(per[level]["cycles"] - ref) / ref if ref else 0.0,
                 "speedup_vs_reference": per[reference]["host_seconds"] / max(per[level]["host_seconds"], 1e-9),
                 "timing_speedup_vs_reference": None if per[level]["timing_seconds"] is None
                 or per[reference]["timing_seconds"] is None
                 else per[reference]["timing_seconds"] / max(per[level]["timing_seconds"], 1e-9)}
            if "interval" in r:
                r["reference_in_interval"] = r["interval"][0] <= ref <= r["interval"][1]
            target = TARGETS.get((scene.stem, level))
            r["target_seconds"] = target
            r["meets_target"] = None if target is None else r["wall_seconds"] <= target
            rows.append(r)
            mark = "" if target is None else (f"  (target <= {target:g} s: {'met' if r['meets_target'] else 'MISSED'})")
            print(f"{scene.stem:<16} {level:<15} wall {r['wall_seconds']:7.2f} s  model {r['host_seconds']:7.2f} s  "
                  f"{r['cycles']:>12,} cycles  {100 * r['cycles_vs_reference']:6.2f} % from {reference}  "
                  f"{r['speedup_vs_reference']:6.1f}x faster{mark}", flush=True)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    machine = f"{platform.node()}, {os.cpu_count()} cores, {cpu_name()}"
    lines = ["# SystemC tiler model: host time per fidelity level", "",
             f"Machine: {machine}. Commit: {commit}. Command: `python3 reports/bench_sim.py --bin {a.bin} --out {a.out}"
             f" --mode {a.mode} --tile {a.tile} --auto-seeds {a.auto_seeds}`. Wall = the whole `tilevis sim` process (trace read, setup, "
             "functional work, simulation, outputs); model = elaboration to results, of which prepare = elaboration "
             "and the functional prepare that every level shares (setup, binning, the units' tables); functional = the "
             "simulation thread's seconds in the functional model (setup, binning, every tile's visibility and results: the "
             "same work at every level, stats.json `host_functional_seconds`), timing = model - functional (elaboration, "
             "SystemC, the units' cost functions, the memory system, and at rtl the Verilated EVU), 'timing faster' = the "
             "reference's timing seconds / the level's. 'tile (replayed)' = fidelity tile replaying the functional pass "
             "a recording run at fidelity tile wrote (`-p sim.functional_record=FILE`, unmeasured; setup, binning and "
             "visibility not computed, the same cycles and outputs): its model seconds include loading the record, "
             "listed with its size below the table. 'tile' and 'analytic' serve memory with the bandwidth model "
             "(memory.model=auto: each channel's bus at 0.9 of its peak), 'tile (detailed memory)' with the DRAM "
             "controller and DRAM model of primitive, rtl and auto. Cycles are the frame's; "
             "'error' is their deviation from the reference level's (rtl; primitive where a build has no "
             "Verilator); 'faster' = the reference's model seconds / the level's. auto: interval = its 95 % "
             "confidence interval, tiles = simulated / in the frame.", "",
             "![speed against accuracy](sim_bench.png)", "",
             "| scene | triangles | level | wall s | model s | prepare s | functional s | timing s | faster | timing faster "
             "| frame cycles | error | auto: interval, tiles |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        extra = ""
        if "interval" in r:
            extra = (f"{r['interval'][0]:,.0f} - {r['interval'][1]:,.0f} "
                     f"({'holds' if r['reference_in_interval'] else 'misses'} the reference), "
                     f"{r['tiles_simulated']:,} / {r['tiles_total']:,}")
            if "geometry_triangles_simulated" in r:
                extra += f"; geometry {r['geometry_triangles_simulated']:,} / {r['triangles']:,} triangles"
        fmt = lambda key, f: "" if r.get(key) is None else f.format(r[key])
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['level']} | {r['wall_seconds']:.2f} | "
                     f"{r['host_seconds']:.2f} | {fmt('prepare_seconds', '{:.2f}')} | {fmt('functional_seconds', '{:.2f}')} | "
                     f"{fmt('timing_seconds', '{:.3f}')} | {r['speedup_vs_reference']:.1f}x | "
                     f"{fmt('timing_speedup_vs_reference', '{:.1f}x')} | {r['cycles']:,} | "
                     f"{100 * r['cycles_vs_reference']:.2f} % | {extra} |")
    replayed = [r for r in rows if r["level"] == REPLAYED]
    if replayed:
        lines += ["", "tile (replayed): the record's size and the seconds loading it took (in its model seconds):", "",
                  "| scene | record MB | load s |", "|---|---|---|"]
        lines += [f"| {r['scene']} | {r['record_bytes'] / 1e6:.1f} | {r['record_load_seconds']:.3f} |" for r in replayed]
    # Per level over the scenes: error and speed against the reference.
    lines += ["", "Per level over the scenes (median and largest error, median and smallest speed-up against the "
              "reference; auto: scenes whose interval holds the reference):", "",
              "| level | scenes | median error | largest error | median faster | slowest faster | median timing faster "
              "| slowest timing faster | interval holds |",
              "|---|---|---|---|---|---|---|---|---|"]
    for level in LEVELS:
        rs = [r for r in rows if r["level"] == level]
        if not rs:
            continue
        errs = sorted(100 * r["cycles_vs_reference"] for r in rs)
        fast = sorted(r["speedup_vs_reference"] for r in rs)
        holds = [r["reference_in_interval"] for r in rs if "reference_in_interval" in r]
        tfast = sorted(r["timing_speedup_vs_reference"] for r in rs if r.get("timing_speedup_vs_reference") is not None)
        ttext = f"{tfast[len(tfast) // 2]:.1f}x | {tfast[0]:.1f}x" if tfast else " | "
        lines.append(f"| {level} | {len(rs)} | {errs[len(errs) // 2]:.2f} % | {errs[-1]:.2f} % | "
                     f"{fast[len(fast) // 2]:.1f}x | {fast[0]:.1f}x | {ttext} | "
                     f"{f'{sum(holds)} of {len(holds)}' if holds else ''} |")
    # auto against the full-detail tile level, per scene: what sampling buys in host time.
    pairs = [(r["scene"], t["host_seconds"] / max(r["host_seconds"], 1e-9), t["wall_seconds"] / max(r["wall_seconds"], 1e-9))
             for r in rows if r["level"] == "auto"
             for t in rows if t["level"] == "tile" and t["scene"] == r["scene"]]
    if pairs:
        lines += ["", "auto against tile (tile's seconds / auto's), model and wall:", "",
                  "| scene | model | wall |", "|---|---|---|"]
        lines += [f"| {sc} | {m:.2f}x | {w:.2f}x |" for sc, m, w in pairs]
    if seeds:
        n = a.auto_seeds
        lines += ["", f"auto on seeds 1 to {n}: signed error against the reference (mean, and the largest in "
                  "size), how often its 95 % interval holds the reference, its model seconds (median), and, where "
                  "the geometry is sampled, the geometry estimate's signed error against the reference's geometry "
                  "(mean, largest):", "",
                  "| scene | mean error | largest error | interval holds | model s | geometry error |",
                  "|---|---|---|---|---|---|"]
        total = 0
        for sc in dict.fromkeys(x["scene"] for x in seeds):
            xs = [x for x in seeds if x["scene"] == sc]
            errs = [100 * x["error"] for x in xs]
            held = sum(x["holds"] for x in xs)
            total += held
            hosts = sorted(x["host_seconds"] for x in xs)
            geo = [100 * x["geometry_error"] for x in xs if x["geometry_error"] is not None]
            geo_text = f"{sum(geo) / len(geo):+.2f} %, {max(geo, key=abs):+.2f} %" if geo else ""
            lines.append(f"| {sc} | {sum(errs) / len(errs):+.2f} % | {max(errs, key=abs):+.2f} % | {held} of {len(xs)} | "
                         f"{hosts[len(hosts) // 2]:.3f} | {geo_text} |")
        lines += ["", f"The interval held the reference in {total} of {len(seeds)} runs "
                  f"({100 * total / len(seeds):.0f} % at 95 % nominal)."]
    if failures:
        lines += ["", "Fidelity rtl failed on (the reference is primitive there):", ""]
        lines += [f"- {k}: `{v}`" for k, v in sorted(failures.items())]
    chart(rows, "rtl", out / "sim_bench.png")
    (out / "sim_bench.md").write_text("\n".join(lines) + "\n")
    (out / "sim_bench.json").write_text(json.dumps({"machine": machine, "commit": commit, "rows": rows,
                                                    "auto_seeds": seeds, "rtl_failures": failures}, indent=2))
    print(f"wrote {out / 'sim_bench.md'}")


if __name__ == "__main__":
    main()
