"""The report's section on workloads given as traces (captured OpenGL programs): imported by
make_report.py, which hands it the points of trace frames and keeps them out of its other
sections (their scenes are built-in scene files; a captured workload is a trace of several
passes, each at its own viewport).

A workload's frame is the sum of its passes: each trace frame (a shadow map, a render-to-texture
pass, the window) is a sweep point of its own, and its fragments and cycles add up to what the
GPU does for the application's frame. Per workload the section gives passes, triangles, the
non-occluding (blended or alpha-tested) share of triangles, overdraw (fragments immediate mode
shades per pixel of every pass), the fragments each visibility mode shades (the z-buffer truth's
none, early-Z and per-pixel HSR; the model's analytic and hybrid), the model's cycles per mode,
the best tile size by the model's cycles, and whether analytic and hybrid equal the truth on
every pass (the sweep's comparisons). It writes OUT/captured.json (the same numbers, for tests
and scripts) and OUT/captured.txt (the table for the terminal).

Python 3 standard library + Debian python3-matplotlib.
"""
import json
from collections import defaultdict

import matplotlib.pyplot as plt

from report_format import fmt_int, fmt_pct, fmt_signed_pct, tile_key

SIM_PRODUCERS = ["sim_tile", "sim_primitive", "sim_analytic"]  # the model's fidelity levels, preferred first
TRUTH_MODES = ["none", "early_z", "hsr"]
EVU_MODES = ["analytic", "hybrid"]
FRAGMENT_TILE = "32x32"  # the tile of the fragment counts and comparisons when the sweep ran it


def trace_points(manifest):
    """dir -> frame for every point of a workload given as a trace."""
    return {p["dir"]: p["frame"] for p in manifest.get("points", []) if "frame" in p}


def split(manifest, rows, scenes):
    """(the trace frames' rows with their frame, the other rows, the other scenes)."""
    frames = trace_points(manifest)
    captured = []
    for r in rows:
        if r.get("dir") in frames:
            captured.append(dict(r, frame=frames[r["dir"]]))
    names = {r["scene"] for r in captured} | set(manifest.get("workloads", {}))
    return captured, [r for r in rows if r.get("dir") not in frames], [s for s in scenes if s not in names]


class Workload:
    """The done points of one workload, by (producer, mode, tile) and frame."""

    def __init__(self, name, info, rows):
        self.name = name
        self.frames = info.get("frames", [])
        self.points = defaultdict(dict)
        for r in rows:
            if r.get("status") == "done" and r.get("config", "default") == "default":
                self.points[(r["producer"], r.get("mode", ""), r["tile"])][int(r["frame"])] = r
        self.rows = rows

    def complete(self, producer, mode, tile):
        """The points of every frame of the trace, or None when one is missing."""
        got = self.points.get((producer, mode, tile), {})
        if not self.frames or any(k not in got for k in range(len(self.frames))):
            return None
        return [got[k] for k in range(len(self.frames))]

    def total(self, producer, mode, tile, column):
        pts = self.complete(producer, mode, tile)
        if pts is None or any(column not in p for p in pts):
            return None
        return sum(p[column] for p in pts)

    def sim(self, mode, tile):
        for prod in SIM_PRODUCERS:
            if self.complete(prod, mode, tile) is not None:
                return prod
        return None

    def tiles(self, producer, mode):
        return sorted({t for (p, m, t) in self.points if p == producer and m == mode
                       and self.complete(p, m, t) is not None}, key=tile_key)

    def fragment_tile(self):
        tiles = sorted({t for (p, m, t) in self.points}, key=tile_key)
        return FRAGMENT_TILE if FRAGMENT_TILE in tiles else (tiles[0] if tiles else None)

    def agreement(self, producer, mode, tile):
        """(frames compared with the truth, frames equal to it, mismatched samples, samples compared)."""
        pts = self.complete(producer, mode, tile)
        if pts is None:
            return None
        n = [p for p in pts if "vs_truth_sample_agreement" in p]
        if len(n) != len(pts):
            return None
        return (len(n), sum(1 for p in n if p.get("vs_truth_mismatched_samples", 1) == 0),
                sum(p.get("vs_truth_mismatched_samples", 0) for p in n),
                sum(p.get("vs_truth_samples_compared", 0) for p in n))


def summarise(w):
    """The numbers of one workload (None where the sweep did not run what they need)."""
    pixels = sum(f["width"] * f["height"] * f.get("samples", 1) for f in w.frames)
    triangles = sum(f["triangles"] for f in w.frames)
    s = {"workload": w.name, "passes": len(w.frames), "pixels": pixels, "triangles": triangles,
         "draws": sum(f["draws"] for f in w.frames),
         "non_occluding_triangles": sum(f["non_occluding_triangles"] for f in w.frames),
         "per_pixel_triangles": sum(f.get("per_pixel_triangles", 0) for f in w.frames),
         "passes_list": [f"{f['width']}x{f['height']}" for f in w.frames]}
    s["non_occluding_share"] = s["non_occluding_triangles"] / triangles if triangles else None
    tile = w.fragment_tile()
    s["tile"] = tile
    fr = {}
    for m in TRUTH_MODES:
        fr[m] = w.total("truth", "", tile, "mode_" + m) if tile else None
    for m in EVU_MODES:
        prod = w.sim(m, tile) if tile else None
        fr[m] = w.total(prod, m, tile, "fragments_shaded") if prod else None
        if fr[m] is None and m == "analytic" and tile:  # the golden pipeline's visible pieces
            fr[m] = w.total("golden", "", tile, "fragments_shaded")
    s["fragments"] = fr
    s["generated"] = w.total("truth", "", tile, "fragments_generated") if tile else None
    s["overdraw"] = fr["none"] / pixels if fr["none"] is not None and pixels else None
    saving = {}
    for m in EVU_MODES:
        if fr[m] is None:
            continue
        for base in TRUTH_MODES:
            if fr[base]:
                saving[f"{m}_vs_{base}"] = 1 - fr[m] / fr[base]
    s["savings"] = saving
    cycles = {}
    for m in EVU_MODES + ["hsr", "early_z", "none"]:
        prod = w.sim(m, tile) if tile else None
        if prod:
            cycles[m] = w.total(prod, m, tile, "cycles")
    s["cycles"] = cycles
    if cycles.get("hybrid") and cycles.get("hsr"):
        s["hybrid_cycle_saving_vs_hsr"] = 1 - cycles["hybrid"] / cycles["hsr"]
    best = {}
    for m in EVU_MODES:
        prod = next((p for p in SIM_PRODUCERS if w.tiles(p, m)), None)
        if not prod:
            continue
        by_tile = {t: w.total(prod, m, t, "cycles") for t in w.tiles(prod, m)}
        by_tile = {t: c for t, c in by_tile.items() if c is not None}
        if by_tile:
            b = min(by_tile, key=lambda t: (by_tile[t], tile_key(t)))
            best[m] = {"tile": b, "cycles": by_tile[b], "cycles_by_tile": by_tile, "producer": prod}
    s["best_tile"] = best
    agree = {}
    for m in EVU_MODES:
        prod = w.sim(m, tile) if tile else None
        a = w.agreement(prod, m, tile) if prod else None
        if a is None and m == "analytic" and tile:
            a, prod = w.agreement("golden", "", tile), "golden"
        if a is not None:
            agree[m] = {"producer": prod, "passes_compared": a[0], "passes_equal": a[1], "mismatched_samples": a[2],
                        "samples_compared": a[3], "equal": a[0] == a[1]}
    s["equals_truth"] = agree
    return s


def section(rep, out, rows, manifest, provenance):
    """Writes the section (when the sweep names traces) and OUT/captured.{json,txt}."""
    sets = manifest.get("trace_sets", {})
    workloads = manifest.get("workloads", {})
    for f in ("captured.json", "captured.txt"):
        (out / f).unlink(missing_ok=True)
    if not sets:
        return None
    rep.heading("Captured workloads: real OpenGL programs as traces", 2, "captured")
    rep.para("Workloads given as trace files (tilevis capture: glmark2's scenes and a game, captured under Xvfb; "
             "traces/capture/README.md). Each trace frame is a render pass (a shadow map, a render-to-texture "
             "pass, the window) and a sweep point of its own at its own viewport; a workload's numbers are the "
             "sums over its passes, what the GPU does for one frame of the application. Overdraw: fragments "
             "immediate mode shades per pixel of all passes. Non-occluding: triangles of blended or alpha-tested "
             "draws (they are shaded and never hide anything). Fragment counts of none, early-Z and per-pixel HSR "
             "come from the z-buffer truth, analytic and hybrid from the model (the golden pipeline where the "
             "model did not run); savings = 1 − shaded / the other mode's shaded.")
    missing = {n: s for n, s in sets.items() if s.get("missing")}
    for n, s in missing.items():
        text = (f"Trace set {n} ({s.get('path')}) was not found when the sweep ran ({s['missing']}): its "
                f"workloads are left out of grids {', '.join(s.get('grids', [])) or '–'}."
                + (f" To make them: {s['make']}" if s.get("make") else ""))
        rep.para(text, "**" + text + "**")
    by_name = defaultdict(list)
    for r in rows:
        by_name[r["scene"]].append(r)
    summaries = [summarise(Workload(n, workloads[n], by_name.get(n, []))) for n in sorted(workloads)]
    (out / "captured.json").write_text(json.dumps({"workloads": summaries, "missing_sets": {
        n: {"path": s.get("path"), "why": s["missing"], "make": s.get("make")} for n, s in missing.items()}},
        indent=1) + "\n")
    if not summaries:
        (out / "captured.txt").write_text("captured workloads: none in this sweep" +
                                          (f" (missing: {', '.join(missing)})" if missing else "") + "\n")
        return summaries

    used = [r for r in rows if r.get("status") == "done"]
    head = ["workload", "passes", "triangles", "non-occluding", "overdraw", "none", "early-Z", "HSR", "analytic",
            "hybrid", "hybrid: fragments saved vs none", "vs early-Z", "vs HSR", "hybrid: cycles saved vs HSR",
            "best tile (hybrid)",
            "best tile (analytic)", "analytic = truth", "hybrid = truth"]
    table = []
    for s in summaries:
        f, sv, eq, b = s["fragments"], s["savings"], s["equals_truth"], s["best_tile"]

        def eq_text(m):
            e = eq.get(m)
            if not e:
                return "–"
            if e["equal"]:
                n = e["passes_compared"]
                return f"yes ({n} pass{'es' if n != 1 else ''})"
            return (f"no: {e['passes_compared'] - e['passes_equal']} of {e['passes_compared']} passes, "
                    f"{e['mismatched_samples']:,} samples")

        table.append([s["workload"], s["passes"], fmt_int(s["triangles"]), fmt_pct(s["non_occluding_share"]),
                      "–" if s["overdraw"] is None else f"{s['overdraw']:.2f}",
                      fmt_int(f["none"]), fmt_int(f["early_z"]), fmt_int(f["hsr"]), fmt_int(f["analytic"]), fmt_int(f["hybrid"]),
                      fmt_pct(sv.get("hybrid_vs_none")), fmt_pct(sv.get("hybrid_vs_early_z")),
                      fmt_signed_pct(sv.get("hybrid_vs_hsr")), fmt_signed_pct(s.get("hybrid_cycle_saving_vs_hsr")),
                      b["hybrid"]["tile"] if "hybrid" in b else "–", b["analytic"]["tile"] if "analytic" in b else "–",
                      eq_text("analytic"), eq_text("hybrid")])
    rep.table(head, table)
    n_h = [s for s in summaries if "hybrid" in s["equals_truth"]]
    n_eq = [s for s in n_h if s["equals_truth"]["hybrid"]["equal"]]
    passes = sum(s["equals_truth"]["hybrid"]["passes_compared"] for s in n_h)
    verdict = (f"Hybrid equals the exact truth on {len(n_eq)} of {len(n_h)} workloads compared ({passes} passes)"
               + ("." if len(n_eq) == len(n_h) else
                  f"; not on {', '.join(s['workload'] for s in n_h if s not in n_eq)}."))
    n_a = [s for s in summaries if "analytic" in s["equals_truth"]]
    a_ne = [s["workload"] for s in n_a if not s["equals_truth"]["analytic"]["equal"]]
    if n_a:
        verdict += (f" Analytic alone equals it on {len(n_a) - len(a_ne)} of {len(n_a)}"
                    + (f" (not on {', '.join(a_ne)})." if a_ne else "."))
    rep.para(verdict, "**" + verdict + "**")
    tiles_text = []
    for s in summaries:
        b = s["best_tile"].get("hybrid") or s["best_tile"].get("analytic")
        if b and len(b["cycles_by_tile"]) > 1:
            tiles_text.append(f"{s['workload']} " + " / ".join(f"{t} {fmt_int(c)}" for t, c in
                                                                sorted(b["cycles_by_tile"].items(),
                                                                       key=lambda kv: tile_key(kv[0]))))
    if tiles_text:
        rep.para("Model cycles per tile size (hybrid, summed over passes): " + "; ".join(tiles_text) + ".")
    rep.para(provenance(used), "*" + provenance(used) + "*")

    # Fragments shaded per pixel, every mode, per workload.
    shown = [s for s in summaries if s["fragments"]["none"]]
    if shown:
        modes = [("none", "immediate (none)"), ("early_z", "early-Z"), ("hsr", "per-pixel HSR"),
                 ("analytic", "analytic"), ("hybrid", "hybrid")]
        fig, ax = plt.subplots(figsize=(12, 4.2))
        width = 0.8 / len(modes)
        for i, (k, label) in enumerate(modes):
            vals = [(s["fragments"][k] or 0) / s["pixels"] for s in shown]
            ax.bar([x + i * width for x in range(len(shown))], vals, width, label=label)
        ax.set_xticks([x + (len(modes) - 1) * width / 2 for x in range(len(shown))])
        ax.set_xticklabels([s["workload"] for s in shown], rotation=30, ha="right", fontsize=8)
        ax.set_ylabel("fragments shaded per pixel (all passes)")
        ax.grid(axis="y", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        rep.figure(fig, "captured", "Captured workloads: fragments shaded per pixel of all passes under each "
                   "visibility mode (immediate mode's bar is the overdraw)", provenance(used))

    short = ["workload", "passes", "triangles", "non-occluding", "overdraw", "hybrid: fragments saved vs none",
             "vs early-Z", "hybrid: cycles saved vs HSR", "best tile (hybrid)", "hybrid = truth"]
    keep = [head.index(h) for h in short]
    cells = [short] + [[str(r[i]) for i in keep] for r in table]
    widths = [max(len(r[i]) for r in cells) for i in range(len(short))]
    text = "\n".join("  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
                     for r in cells)
    (out / "captured.txt").write_text(
        f"captured workloads (sums over each trace's passes; fragments at {summaries[0]['tile']} tiles): "
        + verdict + "\n" + text + "\n"
        + "".join(f"missing: trace set {n}: {s['missing']}" + (f"; to make them: {s['make']}" if s.get("make") else "")
                  + "\n" for n, s in missing.items()))
    return summaries
