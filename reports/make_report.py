#!/usr/bin/python3
"""The report of a TileVis sweep: reads OUT/sweep.json (written by `tilevis sweep`) and every
point's stats.json, process.json, tiles.csv and compare.json, writes OUT/points.csv, then draws
every chart from that CSV with matplotlib and writes OUT/index.html (self-contained: no
network, no scripts; images in OUT/figures/) and OUT/report.md beside it, plus
OUT/best_tiles.{txt,json}.

  python3 reports/make_report.py reports/NAME

Python 3 standard library + Debian python3-matplotlib (numpy comes with it); nothing else.
"""
import csv
import html
import json
import math
import os
import sys
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, TwoSlopeNorm  # noqa: E402

import captured_section  # noqa: E402  (the workloads given as traces: their own section)
from report_format import fmt_int, fmt_pct, tile_key  # noqa: E402
from report_format import fmt_signed_pct as fmt_saving  # noqa: E402

TOTALS = ["triangles_in", "triangles_front", "silhouette_edges", "pair_tests", "candidate_pairs", "clip_polygons",
          "pieces", "visible_pieces", "occlusion_tests", "samples_covered", "fragments_generated",
          "fragments_shaded", "cycles", "param_buffer_bytes", "param_buffer_peak_bytes", "dram_bytes",
          "partial_renders", "evu_busy_cycles", "depth_tests", "tiles_rendered", "samples_tested",
          "memory_bound_share", "dram_utilisation"]
ENERGY = ["total_uj", "dram_uj", "shader_uj", "evu_uj", "depth_test_uj"]  # stats.json totals.energy (the model)
EVU_MODES = ["analytic", "hybrid"]  # the early-visibility unit alone, and with per-pixel fallback tiles
TRUTH_MODES = ["none", "early_z", "early_z_sorted", "prepass", "hsr", "hsr_depth_tests"]
COMPARE_FIELDS = ["sample_agreement", "mismatched_samples", "samples_compared", "max_area_rel_error",
                  "tile_counter_mismatches"]
SIM_PREFERENCE = ["sim_tile", "sim_primitive", "sim_analytic"]
FIDELITY_ORDER = ["sim_analytic", "sim_tile", "sim_primitive"]
TILE_METRICS = [  # (column, label, producer kind, unit)
    ("cycles", "frame cycles", "timing", "cycles"),
    ("pair_tests", "EVU pair tests", "visibility", "tests"),
    ("candidate_pairs", "candidate pairs", "visibility", "pairs"),
    ("pieces", "pieces (SVGPU Fig. 6)", "visibility", "pieces"),
    ("param_buffer_bytes", "parameter-buffer bytes", "timing", "bytes"),
    ("dram_bytes", "DRAM traffic", "timing", "bytes"),
    ("partial_renders", "partial renders", "timing", "renders"),
]


# ------------------------------------------------------------------ reading

def read_json(path):
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


def collect(out):
    """One row per point of the manifest, from the files the producers wrote."""
    manifest = read_json(out / "sweep.json")
    if manifest is None:
        raise SystemExit(f"make_report: {out}/sweep.json missing or unreadable (run `tilevis sweep` first)")
    producers = manifest.get("producers", {})
    planned = {c["dir"] for c in manifest.get("compares", [])}  # a comparison no longer planned is stale
    rows = []
    for p in manifest["points"]:
        d = out / p["dir"]
        r = {k: p[k] for k in ("dir", "grid", "scene", "resolution", "width", "height", "samples", "tile", "tile_w",
                               "tile_h", "producer", "kind", "mode", "config")}
        r["params"] = " ".join(f"{k}={v}" for k, v in sorted(p.get("params", {}).items()))
        stats = read_json(d / "stats.json")
        if stats is None:
            avail = producers.get(p["producer"], {}).get("available", True)
            r["status"] = "missing" if avail else "unavailable"
            rows.append(r)
            continue
        r["status"] = "done"
        totals = stats.get("totals", {})
        for k in TOTALS:
            if k in totals:
                r[k] = totals[k]
        for k in ENERGY:
            if k in totals.get("energy", {}):
                r["energy_" + k] = totals["energy"][k]
        for k in TRUTH_MODES:
            if k in stats.get("modes", {}):
                r["mode_" + k] = stats["modes"][k]
        r["host_seconds"] = stats.get("host_seconds")
        # Time per frame: the producer's own measure (CUDA: GPU time of the pipeline).
        r["frame_seconds"] = stats["total_ms"] / 1e3 if "total_ms" in stats else stats.get("host_seconds")
        if "frame_seconds_at_clock" in stats:
            r["frame_seconds_at_clock"] = stats["frame_seconds_at_clock"]
        if "device" in stats and isinstance(stats["device"], str):
            r["device"] = stats["device"]
        proc = read_json(d / "process.json") or {}
        for k in ("wall_seconds", "cpu_seconds", "max_rss_mib", "commit", "finished"):
            if k in proc:
                r[k] = proc[k]
        m = proc.get("machine", {})
        if m:
            r["machine"] = f"{m.get('host', '?')}: {m.get('cpu', '?')}, {m.get('cores', '?')} cores"
        for c in sorted(d.glob("vs-*/compare.json")):
            if str(c.parent.relative_to(out)) not in planned:
                continue
            cj = read_json(c)
            if cj is None:
                continue
            b = c.parent.name[3:]
            for k in COMPARE_FIELDS:
                if k in cj:
                    r[f"vs_{b}_{k}"] = cj[k]
            if cj.get("mismatch_causes"):
                r[f"vs_{b}_causes"] = "; ".join(f"{n} {k}" for k, n in cj["mismatch_causes"].items())
        rows.append(r)
    return manifest, rows


def write_csv(rows, path):
    cols = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow(r)


def read_csv(path):
    """Charts and tables are made from the CSV (numbers back to numbers)."""
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            out = {}
            for k, v in r.items():
                if v == "" or v is None:
                    continue
                if k in ("tile", "resolution", "commit", "dir", "scene", "producer", "mode", "config", "grid",
                         "params", "status", "kind", "machine", "finished", "device") or k.endswith("_causes"):
                    out[k] = v
                    continue
                try:
                    x = float(v)
                    out[k] = int(x) if x.is_integer() and "seconds" not in k and "error" not in k \
                        and "agreement" not in k else x
                except ValueError:
                    out[k] = v
            rows.append(out)
    return rows


# ------------------------------------------------------------------ helpers

def fmt_s(x):
    if x is None:
        return "–"
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def fmt_bytes(x):
    if x is None:
        return "–"
    for unit, div in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if x >= div:
            return f"{x / div:.1f} {unit}"
    return f"{int(x)} B"


def res_key(r):
    w, h = (int(v) for v in r.split("x"))
    return (w * h, w)


def res_name(r):
    return {"1920x1080": "1080p", "3840x2160": "4K", "1280x720": "720p"}.get(r, r)


def res_title(r):
    n = res_name(r)
    return r if n == r else f"{n} ({r})"


class Report:
    """Blocks rendered twice: HTML (index.html) and Markdown (report.md)."""

    def __init__(self, out, manifest):
        self.out = out
        self.manifest = manifest
        self.html = []
        self.md = []
        self.figures = []
        (out / "figures").mkdir(exist_ok=True)

    def heading(self, text, level=2, anchor=None):
        a = f' id="{anchor}"' if anchor else ""
        self.html.append(f"<h{level}{a}>{html.escape(text)}</h{level}>")
        self.md.append("#" * level + " " + text + "\n")

    def para(self, text, md=None):
        self.html.append(f"<p>{html.escape(text)}</p>")
        self.md.append((md or text) + "\n")

    def table(self, head, rows, numeric_from=1):
        h = ['<div class="wide"><table><thead><tr>' + "".join(f"<th>{html.escape(str(c))}</th>" for c in head) + "</tr></thead><tbody>"]
        for r in rows:
            cells = []
            for i, c in enumerate(r):
                cls = ' class="n"' if i >= numeric_from else ""
                cells.append(f"<td{cls}>{html.escape(str(c))}</td>")
            h.append("<tr>" + "".join(cells) + "</tr>")
        h.append("</tbody></table></div>")
        self.html.append("\n".join(h))
        md = ["| " + " | ".join(str(c) for c in head) + " |", "|" + "---|" * len(head)]
        md += ["| " + " | ".join(str(c).replace("|", "/") for c in r) + " |" for r in rows]
        self.md.append("\n".join(md) + "\n")

    def figure(self, fig, name, caption, provenance):
        path = self.out / "figures" / f"{name}.png"
        fig.savefig(path, dpi=96, bbox_inches="tight")
        plt.close(fig)
        self.figures.append(path)
        src = f"figures/{name}.png"
        self.html.append(f'<figure><img src="{src}" alt="{html.escape(caption)}">'
                         f"<figcaption>{html.escape(caption)}<br><span class=\"prov\">{html.escape(provenance)}</span>"
                         "</figcaption></figure>")
        self.md.append(f"![{caption}]({src})\n\n*{caption}* — {provenance}\n")

    def write(self, title):
        css = """body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.2em;font-size:13px}th,td{border:1px solid #ccc;padding:2px 6px}
th{background:#f0f0f0}td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}figure{margin:1em 0}
figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:13px;color:#444}.prov{color:#777;font-size:12px}
code{background:#f4f4f4;padding:0 3px}nav a{margin-right:1em}
div.wide{overflow-x:auto;max-width:100%}th{position:sticky;top:0}"""
        doc = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
               '<link rel="icon" href="data:,">', f"<title>{html.escape(title)}</title>", f"<style>{css}</style>",
               "</head><body>", *self.html, "</body></html>"]
        (self.out / "index.html").write_text("\n".join(doc) + "\n")
        (self.out / "report.md").write_text("\n".join(self.md))


def provenance(points, configs=None):
    """Machine, commit and config of the points behind a figure or table."""
    machines = sorted({p.get("machine", "?") + (f" + GPU {p['device']}" if p.get("device") else "")
                       for p in points if p.get("status") == "done"})
    commits = sorted({p.get("commit", "?") for p in points if p.get("status") == "done"})
    cfgs = sorted({(p.get("config", "default"), p.get("params", "")) for p in points if p.get("status") == "done"})
    cfg_text = ", ".join(f"{c}" + (f" ({params})" if params else "") for c, params in cfgs) or "default"
    res = sorted({p["resolution"] for p in points}, key=res_key)
    spp = sorted({int(p["samples"]) for p in points})
    tiles = sorted({p["tile"] for p in points}, key=tile_key)
    prods = sorted({p["producer"] + (f"[{p['mode']}]" if p.get("mode") else "") for p in points})
    return (f"Points: {len(points)} ({', '.join(prods)}; {', '.join(res)}; {', '.join(map(str, spp))} spp; "
            f"tiles {', '.join(tiles)}; config {cfg_text}). Machine: {'; '.join(machines) or '?'}. "
            f"Commit: {', '.join(commits) or '?'}.")


# ------------------------------------------------------------------ the sections

def pick(rows, **want):
    return [r for r in rows if r.get("status") == "done" and all(r.get(k) == v for k, v in want.items())]


def first(rows, **want):
    got = pick(rows, **want)
    return got[0] if got else None


def preferred_tile(points):
    tiles = sorted({p["tile"] for p in points}, key=tile_key)
    if "32x32" in tiles:
        return "32x32"
    return tiles[0] if tiles else None


def sim_point(rows, scene, res, spp, tile, mode="analytic", config="default"):
    for prod in SIM_PREFERENCE:
        p = first(rows, scene=scene, resolution=res, samples=spp, tile=tile, producer=prod, mode=mode, config=config)
        if p:
            return p
    return None


def text_table(head, rows):
    """A plain-text table, numbers right-aligned (for the terminal)."""
    cells = [head] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
                     for r in cells) + "\n"


def section_savings(rep, rows, scenes, out):
    rep.heading("Fragment work: what early visibility saves", 2, "savings")
    rep.para("Generated fragments are every covered sample of every front-facing triangle (what immediate mode "
             "shades). Early-Z, early-Z sorted, pre-pass and per-pixel HSR counts come from the z-buffer truth; "
             "analytic is the golden SVGPU pipeline's visible pieces; savings = 1 − shaded / generated. The "
             "visibility unit's own work is the golden pipeline's pair tests, clips and occlusion tests; cycles "
             "come from the SystemC model (fidelity tile) where it ran.")
    combos = sorted({(r["resolution"], int(r["samples"])) for r in rows
                     if r.get("status") == "done" and r["producer"] in ("truth", "golden")},
                    key=lambda c: (res_key(c[0]), c[1]))
    sim_modes = sorted({r["mode"] for r in rows if r.get("status") == "done" and r.get("kind") == "timing"
                        and r.get("mode")})
    summary = defaultdict(dict)
    all_used = []
    for res, spp in combos:
        used, table = [], []
        for scene in scenes:
            truth = first(rows, scene=scene, resolution=res, samples=spp, producer="truth", tile="32x32") or \
                first(rows, scene=scene, resolution=res, samples=spp, producer="truth")
            goldens = pick(rows, scene=scene, resolution=res, samples=spp, producer="golden")
            tile = preferred_tile(goldens) if goldens else None
            golden = first(rows, scene=scene, resolution=res, samples=spp, producer="golden", tile=tile) if tile else None
            if not truth and not golden:
                continue
            used += [p for p in (truth, golden) if p]
            gen = (truth or golden).get("fragments_generated")
            m = {k: truth.get("mode_" + k) for k in ("early_z", "early_z_sorted", "hsr")} if truth else {}
            analytic = golden.get("fragments_shaded") if golden else None
            sav = lambda x: (1 - x / gen) if (x is not None and gen) else None  # noqa: E731
            cycles = []
            for mode in sim_modes:
                sp = sim_point(rows, scene, res, spp, tile or "32x32", mode=mode)
                if sp:
                    used.append(sp)
                cycles.append(fmt_int(sp.get("cycles")) if sp else "–")
            sa = sim_point(rows, scene, res, spp, tile or "32x32")
            cycles.append(fmt_int(sa.get("evu_busy_cycles")) if sa else "–")
            summary[scene][(res, spp)] = {"generated": gen, "analytic": sav(analytic), "hsr": sav(m.get("hsr")),
                                          "early_z": sav(m.get("early_z")),
                                          "early_z_sorted": sav(m.get("early_z_sorted"))}
            table.append([scene, fmt_int((truth or golden).get("triangles_in")), fmt_int(gen),
                          fmt_int(m.get("early_z")), fmt_int(m.get("early_z_sorted")), fmt_int(m.get("hsr")),
                          fmt_int(analytic), fmt_pct(sav(m.get("early_z"))), fmt_pct(sav(m.get("hsr"))),
                          fmt_pct(sav(analytic)), fmt_int(golden.get("pair_tests") if golden else None),
                          fmt_int(golden.get("clip_polygons") if golden else None),
                          fmt_int(golden.get("occlusion_tests") if golden else None), *cycles])
        if not table:
            continue
        rep.heading(f"{res_title(res)}, {spp} sample{'s' if spp > 1 else ''} per pixel", 3)
        head = ["scene", "triangles", "generated", "early-Z", "early-Z sorted", "HSR / prepass", "analytic",
                "saved: early-Z", "saved: HSR", "saved: analytic", "EVU pair tests", "EVU clips",
                "EVU occlusion tests"] + [f"frame cycles ({m})" for m in sim_modes] + ["EVU busy cycles"]
        rep.table(head, table)
        rep.para(provenance(used), "*" + provenance(used) + "*")
        if not all_used:  # the first resolution x samples, for the terminal (./tilevis demo prints it)
            names = ["scene", "generated", "early-Z", "HSR / prepass", "analytic", "saved: analytic"]
            keep = [head.index(n) for n in names] + [i for i, h in enumerate(head) if "cycles" in h]
            tiles = ", ".join(sorted({p["tile"] for p in used if p["producer"] == "golden"}, key=tile_key))
            (out / "fragment_work.txt").write_text(
                f"{res_title(res)}, {spp} spp, tiles {tiles}: fragments generated and shaded per mode, "
                "analytic savings, the model's frame cycles per mode and EVU busy cycles\n" +
                text_table([head[i] for i in keep], [[r[i] for i in keep] for r in table]))
        all_used += used
    # Savings per mode at the first resolution x samples, and analytic savings at each of them.
    if summary:
        scenes_with = [s for s in scenes if s in summary]
        x = np.arange(len(scenes_with))
        fig, axes = plt.subplots(1, 2, figsize=(13, 4.2), squeeze=False)
        ax = axes[0][0]
        modes = [("early_z", "early-Z"), ("early_z_sorted", "early-Z sorted"), ("hsr", "HSR / prepass"),
                 ("analytic", "analytic")]
        width = 0.8 / len(modes)
        c0 = combos[0]
        for i, (k, label) in enumerate(modes):
            vals = [100 * (summary[s].get(c0, {}).get(k) or 0) for s in scenes_with]
            ax.bar(x + i * width, vals, width, label=label)
        ax.set_title(f"savings per visibility mode, {res_name(c0[0])}, {c0[1]} spp", fontsize=10)
        ax2 = axes[0][1]
        width2 = 0.8 / max(1, len(combos))
        for i, (res, spp) in enumerate(combos):
            vals = [100 * (summary[s].get((res, spp), {}).get("analytic") or 0) for s in scenes_with]
            ax2.bar(x + i * width2, vals, width2, label=f"{res_name(res)}, {spp} spp")
        ax2.set_title("analytic savings per resolution and sample count", fontsize=10)
        for a_, centre in ((ax, (len(modes) - 1) * width / 2), (ax2, (len(combos) - 1) * width2 / 2)):
            a_.set_xticks(x + centre)
            a_.set_xticklabels(scenes_with, rotation=25, fontsize=8)
            a_.set_ylabel("fragment work saved (%)")
            a_.set_ylim(0, 105)
            a_.grid(axis="y", alpha=0.3)
            a_.legend(fontsize=8)
        fig.tight_layout()
        pts = [r for r in all_used if r["producer"] in ("truth", "golden")]
        rep.figure(fig, "savings", "Fragment work saved against immediate mode (1 − shaded / generated): by "
                   "visibility mode, and the analytic unit's savings at each resolution and sample count",
                   provenance(pts))
    return summary


def tile_points(rows, scene):
    """The resolution x samples with the most tile sizes, and its golden and sim points per tile."""
    by_combo = defaultdict(set)
    for r in pick(rows, scene=scene):
        if r["producer"] == "golden" or r.get("kind") == "timing":
            by_combo[(r["resolution"], int(r["samples"]))].add(r["tile"])
    if not by_combo:
        return None
    res, spp = max(by_combo, key=lambda c: (len(by_combo[c]), -res_key(c[0])[0], -c[1]))
    tiles = sorted(by_combo[(res, spp)], key=tile_key)
    if len(tiles) < 2:
        return None
    out = {}
    for t in tiles:
        out[t] = {"golden": first(rows, scene=scene, resolution=res, samples=spp, tile=t, producer="golden"),
                  "sim": sim_point(rows, scene, res, spp, t)}
    return res, spp, tiles, out


def section_tiles(rep, rows, scenes):
    rep.heading("Tile size", 2, "tiles")
    rep.para("Per scene, against tile size: the early-visibility unit's pair tests and candidate pairs and the "
             "pieces it produces (golden; SVGPU Fig. 6 shows the same growth of output with smaller tiles), and, "
             "where the SystemC model ran (fidelity tile, analytic mode, default configuration), frame cycles, "
             "parameter-buffer bytes, DRAM traffic and partial renders.")
    best = {}
    sentences = []
    for scene in scenes:
        tp = tile_points(rows, scene)
        if not tp:
            continue
        res, spp, tiles, pts = tp
        metrics = []
        for col, label, kind, unit in TILE_METRICS:
            src = "sim" if kind == "timing" else "golden"
            vals = [pts[t][src].get(col) if pts[t][src] else None for t in tiles]
            if all(v is None for v in vals):
                continue
            metrics.append((col, label, unit, vals))
        if not metrics:
            continue
        n = len(metrics)
        cols = min(4, n)
        nrows = math.ceil(n / cols)
        fig, axes = plt.subplots(nrows, cols, figsize=(3.4 * cols, 2.8 * nrows), squeeze=False)
        for i, (col, label, unit, vals) in enumerate(metrics):
            ax = axes[i // cols][i % cols]
            xs = [j for j, v in enumerate(vals) if v is not None]
            ax.plot(xs, [vals[j] for j in xs], "o-")
            ax.set_xticks(range(len(tiles)))
            ax.set_xticklabels(tiles, rotation=45, fontsize=8)
            ax.set_title(label, fontsize=10)
            ax.grid(alpha=0.3)
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
        for j in range(n, nrows * cols):
            axes[j // cols][j % cols].axis("off")
        fig.suptitle(f"{scene}: {res}, {spp} spp", fontsize=11)
        fig.tight_layout()
        used = [p for t in tiles for p in pts[t].values() if p]
        rep.heading(scene, 3)
        rep.figure(fig, f"tiles_{scene}", f"{scene}: early-visibility work, memory and cycles against tile size "
                   f"({res}, {spp} spp)", provenance(used))
        head = ["tile"] + [m[1] for m in metrics]
        table = []
        for j, t in enumerate(tiles):
            table.append([t] + [fmt_bytes(m[3][j]) if m[2] == "bytes" else fmt_int(m[3][j]) for m in metrics])
        rep.table(head, table)
        # Best tile per metric.
        best[scene] = {"resolution": res, "samples": spp}
        parts = []
        for col, label, unit, vals in metrics:
            valid = [(v, tile_key(t), t) for t, v in zip(tiles, vals) if v is not None]
            if not valid or all(v == valid[0][0] for v, _, _ in valid):
                if valid:
                    parts.append(f"{label} do not depend on the tile size here ({fmt_int(valid[0][0])})")
                continue
            v, _, t = min(valid)
            best[scene][col] = {"tile": t, "value": v}
            ref = dict((tt, vv) for vv, _, tt in valid).get("32x32")
            rel = f", {100 * (1 - v / ref):.1f} % below 32x32" if ref and t != "32x32" and ref > 0 else ""
            parts.append(f"the {'least' if unit == 'bytes' else 'fewest'} {label} at {t} "
                         f"({fmt_bytes(v) if unit == 'bytes' else fmt_int(v)}{rel})")
        headline = next((c for c in ("cycles", "pair_tests", "pieces") if c in best[scene]), None)
        if headline:
            best[scene]["best"] = {"tile": best[scene][headline]["tile"], "metric": headline,
                                   "value": best[scene][headline]["value"]}
        s = f"{scene} ({res}, {spp} spp): " + "; ".join(parts) + "."
        sentences.append(s)
        rep.para(s)
    if sentences:
        rep.heading("Best tile size per scene", 3, "best")
        table = []
        for scene, b in best.items():
            row = [scene, b.get("best", {}).get("tile", "–"), b.get("best", {}).get("metric", "–")]
            for col, label, _, _ in TILE_METRICS:
                row.append(b[col]["tile"] if col in b else "–")
            table.append(row)
        rep.table(["scene", "best tile", "by"] + [m[1] for m in TILE_METRICS], table, numeric_from=99)
    return best


def read_tiles(path):
    with open(path, newline="") as f:
        rd = csv.DictReader(f)
        rows = list(rd)
    if not rows:
        return None
    tx = np.array([int(r["tx"]) for r in rows])
    ty = np.array([int(r["ty"]) for r in rows])
    grid = {}
    for col in rows[0]:
        if col in ("tx", "ty", "x0", "y0"):
            continue
        a = np.zeros((ty.max() + 1, tx.max() + 1))
        a[ty, tx] = [float(r[col]) for r in rows]
        grid[col] = a
    return grid


def section_heatmaps(rep, out, rows, scenes):
    rep.heading("Per-tile heatmaps", 2, "heatmaps")
    rep.para("Per tile: the SystemC model's cycles (where it ran), the golden pipeline's pieces and pair tests, and "
             "overdraw = fragments generated per covered pixel sample (the per-tile sum of the truth's "
             "overdraw.exr, from tiles.csv). The per-sample images stay in the point folders as EXR "
             "(truth: overdraw.exr, ids.exr; sim: tile_cycles.exr).")
    for scene in scenes:
        goldens = pick(rows, scene=scene, producer="golden")
        if not goldens:
            continue
        combos = sorted({(g["resolution"], int(g["samples"])) for g in goldens}, key=lambda c: (res_key(c[0]), c[1]))
        res, spp = combos[0]
        tile = preferred_tile([g for g in goldens if (g["resolution"], int(g["samples"])) == (res, spp)])
        golden = first(rows, scene=scene, resolution=res, samples=spp, producer="golden", tile=tile)
        sim = sim_point(rows, scene, res, spp, tile)
        truth = first(rows, scene=scene, resolution=res, samples=spp, producer="truth", tile=tile)
        panels = []
        if sim:
            g = read_tiles(out / sim["dir"] / "tiles.csv")
            if g and "tile_cycles" in g:
                panels.append(("cycles (sim)", g["tile_cycles"]))
        g = read_tiles(out / golden["dir"] / "tiles.csv")
        if not g:
            continue
        panels.append(("pieces (golden)", g["pieces"]))
        panels.append(("pair tests (golden)", g["pair_tests"]))
        tsrc = read_tiles(out / truth["dir"] / "tiles.csv") if truth else None
        frag = (tsrc or g)["fragments_generated"]
        tw, th = (int(v) for v in tile.split("x"))
        w, h = (int(v) for v in res.split("x"))
        area = np.zeros_like(frag)
        for ty in range(frag.shape[0]):
            for tx in range(frag.shape[1]):
                area[ty, tx] = max(0, min(tw, w - tx * tw)) * max(0, min(th, h - ty * th))
        panels.append(("overdraw (fragments / sample)", frag / np.maximum(area * spp, 1)))
        fig, axes = plt.subplots(1, len(panels), figsize=(4.3 * len(panels), 2.9), squeeze=False)
        for ax, (label, a) in zip(axes[0], panels):
            masked = np.ma.masked_less_equal(a, 0)
            if masked.count() and masked.max() > masked.min() > 0:
                im = ax.imshow(masked, cmap="inferno", norm=LogNorm(vmin=masked.min(), vmax=masked.max()),
                               interpolation="nearest")
            else:
                im = ax.imshow(a, cmap="inferno", interpolation="nearest")
            ax.set_title(label, fontsize=10)
            ax.set_xticks([])
            ax.set_yticks([])
            fig.colorbar(im, ax=ax, fraction=0.035, pad=0.02)
        fig.suptitle(f"{scene}: {res}, {spp} spp, {tile} tiles (log colour scale)", fontsize=11)
        fig.tight_layout()
        used = [p for p in (golden, sim, truth) if p]
        rep.figure(fig, f"heatmap_{scene}", f"{scene}: per-tile work and overdraw", provenance(used))


def section_crosscheck(rep, rows, manifest):
    rep.heading("Cross-check: golden, truth, SystemC model, CUDA", 2, "crosscheck")
    unavailable = {n: p.get("why", "") for n, p in manifest.get("producers", {}).items() if not p.get("available", True)}
    if unavailable:
        rep.para("Not run here: " + "; ".join(f"{n} ({why})" for n, why in sorted(unavailable.items())) + ".")
    groups = defaultdict(list)
    for r in rows:
        if r.get("status") != "done":
            continue
        for k in r:
            if k.startswith("vs_") and k.endswith("_sample_agreement"):
                groups[(r["producer"], k[3:-len("_sample_agreement")])].append(r)
    if not groups:
        rep.para("No comparisons in this sweep.")
        return
    summary = []
    for (a, b), pts in sorted(groups.items()):
        # One row per mode and configuration: a partial render, say, changes tile counters, not ids.
        by_setting = defaultdict(list)
        for p in pts:
            by_setting[(p.get("mode") or "", p.get("config") or "default")].append(p)
        for (mode, config), ps in sorted(by_setting.items()):
            exact = sum(1 for p in ps if p.get(f"vs_{b}_mismatched_samples", 1) == 0)
            tc = sum(1 for p in ps if p.get(f"vs_{b}_tile_counter_mismatches", 1) == 0)
            worst = min(p[f"vs_{b}_sample_agreement"] for p in ps)
            summary.append([a + (f"[{mode}]" if mode else ""), b, config, len(ps), f"{exact} of {len(ps)}",
                            f"{tc} of {len(ps)}", f"{100 * worst:.5f} %"])
    rep.table(["producer", "against", "config", "points", "identical ids",
               "identical tile counters (shared columns)", "worst sample agreement"], summary, numeric_from=3)
    rep.para("Identical ids are expected of cuda_exact and sim (analytic mode) against golden, and of the z-buffer "
             "modes (early_z, hsr, none) against truth; golden differs from truth only where triangles "
             "interpenetrate (the causes column below); a partial render (a small parameter buffer) splits a tile's "
             "work into passes, so its per-tile counters differ while its ids stay identical; float and quantised "
             "depth are measured, not expected to agree.")
    table = []
    for (a, b), pts in sorted(groups.items()):
        for p in sorted(pts, key=lambda p: (p["scene"], res_key(p["resolution"]), p["samples"], tile_key(p["tile"]))):
            err = p.get(f"vs_{b}_max_area_rel_error")
            table.append([p["scene"], f"{a}{'[' + p['mode'] + ']' if p.get('mode') else ''}", b, p["resolution"],
                          p["samples"], p["tile"], f"{100 * p[f'vs_{b}_sample_agreement']:.5f} %",
                          fmt_int(p.get(f"vs_{b}_mismatched_samples")), fmt_int(p.get(f"vs_{b}_samples_compared")),
                          "–" if err is None or (isinstance(err, float) and math.isnan(err)) else f"{err:.2g}",
                          fmt_int(p.get(f"vs_{b}_tile_counter_mismatches")), p.get(f"vs_{b}_causes", "")])
    rep.table(["scene", "producer", "against", "resolution", "spp", "tile", "sample agreement", "mismatched",
               "compared", "max area rel. error", "tile counter cells differing", "mismatch causes"], table,
              numeric_from=3)
    rep.para(provenance([p for pts in groups.values() for p in pts]),
             "*" + provenance([p for pts in groups.values() for p in pts]) + "*")


def section_speed_accuracy(rep, rows):
    rep.heading("Speed against accuracy", 2, "speed")
    rep.para("Each producer and setting: its time per frame (host seconds of the producer's own work; CUDA: GPU "
             "time) against its error. Visibility error is the share of covered samples whose visible triangle "
             "differs from the exact z-buffer truth (truth with depth rounded to 16 or 24 bits is a producer with "
             "an error, like hardware). Timing error is |cycles − cycles at fidelity primitive| / cycles at "
             "fidelity primitive, the most detailed level modelled (RTL co-simulation is not part of the sweep).")
    floor = 1e-7
    vis = defaultdict(list)
    for r in rows:
        if r.get("status") != "done" or r.get("frame_seconds") is None:
            continue
        name = r["producer"] + (f"[{r['mode']}]" if r.get("mode") and r["mode"] != "analytic" else "")
        if r["producer"] == "truth":
            vis["truth (exact, reference)"].append((r["frame_seconds"], 0.0, r))
        elif "vs_truth_sample_agreement" in r:
            vis[name].append((r["frame_seconds"], 1 - r["vs_truth_sample_agreement"], r))
    timing = defaultdict(list)
    for r in rows:
        if r.get("status") != "done" or r.get("kind") != "timing" or r.get("cycles") is None:
            continue
        ref = first(rows, scene=r["scene"], resolution=r["resolution"], samples=r["samples"], tile=r["tile"],
                    mode=r.get("mode"), config=r.get("config"), producer="sim_primitive")
        if not ref or not ref.get("cycles"):
            continue
        timing[r["producer"]].append((r["frame_seconds"], abs(r["cycles"] - ref["cycles"]) / ref["cycles"], r))
    panels = [(t, d) for t, d in (("visibility: sample disagreement with the exact truth", vis),
                                  ("timing: cycle difference from fidelity primitive", timing)) if d]
    if not panels:
        rep.para("No producer in this sweep has an accuracy figure.")
        return
    fig, axes = plt.subplots(1, len(panels), figsize=(6.2 * len(panels), 4.4), squeeze=False)
    table = []
    used = []
    for ax, (title, data) in zip(axes[0], panels):
        order = sorted(data, key=lambda k: FIDELITY_ORDER.index(k) if k in FIDELITY_ORDER else -1)
        colors = plt.get_cmap("tab20" if len(order) > 10 else "tab10").colors  # one colour per producer
        for i, name in enumerate(order):
            pts = data[name]
            xs = [p[0] for p in pts]
            ys = [max(p[1], floor) for p in pts]
            ax.scatter(xs, ys, s=18, alpha=0.55, label=name, color=colors[i % len(colors)])
            mx, my = float(np.median(xs)), float(np.mean([p[1] for p in pts]))
            ax.scatter([mx], [max(my, floor)], s=140, marker="*", color=colors[i % len(colors)], edgecolor="k", zorder=4)
            used += [p[2] for p in pts]
            table.append([title.split(":")[0], name, len(pts), fmt_s(mx), f"{100 * my:.5f} %",
                          f"{100 * max(p[1] for p in pts):.5f} %"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.axhline(floor, color="grey", lw=0.8, ls=":")
        ax.text(ax.get_xlim()[0], floor, " exact (0)", va="bottom", fontsize=8, color="grey")
        ax.set_xlabel("time per frame (s)")
        ax.set_ylabel("error (fraction)")
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.tight_layout()
    rep.figure(fig, "speed_accuracy", "Speed against accuracy: every point of every producer (dots: one scene and "
               "setting each; stars: median time, mean error); errors of 0 are drawn on the dotted line",
               provenance(used))
    rep.table(["error", "producer", "points", "median s / frame", "mean error", "worst error"], table, numeric_from=2)


# ------------------------------------------------------------------ crossover: the EVU against per-pixel HSR

def saving(evu, hsr, col="cycles"):
    """What the EVU saves over per-pixel HSR at the same setting: 1 - EVU / HSR (negative: it costs more)."""
    a, b = (evu or {}).get(col), (hsr or {}).get(col)
    return (1 - a / b) if a is not None and b else None


def crossover_settings(rows):
    """Every setting (scene, resolution, spp, tile, config) the model ran in mode hsr and in an EVU mode, at the
    most detailed-per-second producer available (SIM_PREFERENCE): {setting: {mode: point}}."""
    by = defaultdict(lambda: defaultdict(dict))
    for r in rows:
        if r.get("status") == "done" and r.get("kind") == "timing" and r.get("cycles") and r.get("mode"):
            key = (r["scene"], r["resolution"], int(r["samples"]), r["tile"], r.get("config", "default"))
            by[key][r["producer"]][r["mode"]] = r
    out = {}
    for key, prods in by.items():
        for prod in SIM_PREFERENCE + sorted(prods):
            modes = prods.get(prod, {})
            if "hsr" in modes and any(m in modes for m in EVU_MODES):
                out[key] = modes
                break
    return out


def crossover_heatmaps(rep, settings, scenes):
    """Scenes x (resolution, samples) at the default configuration and the preferred tile: the EVU's saving
    over HSR in cycles and in the energy proxy."""
    tile = preferred_tile([{"tile": k[3]} for k in settings])
    combos = sorted({(k[1], k[2]) for k in settings if k[3] == tile and k[4] == "default"},
                    key=lambda c: (res_key(c[0]), c[1]))
    names = [s for s in scenes if any(k[0] == s and k[3] == tile and k[4] == "default" for k in settings)]
    if not combos or not names:
        return []
    panels = [("cycles", "frame cycles"), ("energy_total_uj", "energy proxy (DRAM + shader + EVU + depth tests)")]
    fig, axes = plt.subplots(1, 2, figsize=(max(9, 1.2 * len(combos) * 2 + 4), 0.42 * len(names) + 2.2),
                             squeeze=False)
    used = []
    for ax, (col, title) in zip(axes[0], panels):
        m = np.full((len(names), len(combos)), np.nan)
        for i, s in enumerate(names):
            for j, (res, spp) in enumerate(combos):
                modes = settings.get((s, res, spp, tile, "default"), {})
                v = saving(modes.get("analytic"), modes.get("hsr"), col)
                if v is not None:
                    m[i, j] = v
                    used += [modes["analytic"], modes["hsr"]]
        finite = m[np.isfinite(m)]
        lo = min(-0.05, float(finite.min())) if finite.size else -1
        hi = max(0.05, float(finite.max())) if finite.size else 1
        im = ax.imshow(m, cmap="RdYlGn", norm=TwoSlopeNorm(vcenter=0.0, vmin=lo, vmax=hi), aspect="auto")
        for i in range(len(names)):
            for j in range(len(combos)):
                if np.isfinite(m[i, j]):
                    ax.text(j, i, f"{100 * m[i, j]:+.0f}", ha="center", va="center", fontsize=7)
        ax.set_xticks(range(len(combos)))
        ax.set_xticklabels([f"{res_name(r)}\n{n} spp" for r, n in combos], fontsize=8)
        ax.set_yticks(range(len(names)))
        ax.set_yticklabels(names, fontsize=8)
        ax.set_title(f"EVU saving over HSR: {title}", fontsize=10)
        fig.colorbar(im, ax=ax, fraction=0.04, format=lambda x, _: f"{100 * x:+.0f} %")
    fig.tight_layout()
    rep.figure(fig, "crossover", f"Where the EVU wins: 1 − EVU / HSR in frame cycles and in energy, per scene and "
               f"resolution × samples (green: the EVU is cheaper; numbers in %; mode analytic against mode hsr, "
               f"tiles {tile}, default configuration)", provenance(used))
    return used


def crossover_params(rep, settings, scenes):
    """One unit parameter at a time: the EVU's saving per configuration at the operating point with the most
    configurations, with the share of the frame bound by memory."""
    counts = defaultdict(set)
    for k in settings:
        counts[(k[1], k[2], k[3])].add(k[4])
    point = max(counts, key=lambda c: (len(counts[c]), c[2] == "32x32"), default=None)
    if point is None or len(counts[point]) < 3:
        return []
    res, spp, tile = point
    configs = ["default"] + sorted(c for c in counts[point] if c != "default")
    names = [s for s in scenes if (s, res, spp, tile, "default") in settings]
    fig, ax = plt.subplots(figsize=(max(8, 0.7 * len(configs) + 3), 4.4))
    colors = plt.get_cmap("tab20").colors
    table, used = [], []
    for i, s in enumerate(names):
        ys = []
        for c in configs:
            modes = settings.get((s, res, spp, tile, c), {})
            evu, hsr = modes.get("analytic"), modes.get("hsr")
            v = saving(evu, hsr)
            ys.append(np.nan if v is None else 100 * v)
            if v is None:
                continue
            used += [evu, hsr]
            table.append([s, c, fmt_int(evu["cycles"]), fmt_int(hsr["cycles"]), fmt_saving(v),
                          fmt_pct(evu.get("memory_bound_share")), fmt_pct(hsr.get("memory_bound_share")),
                          fmt_bytes(evu.get("dram_bytes")), fmt_bytes(hsr.get("dram_bytes")),
                          fmt_saving(saving(evu, hsr, "energy_total_uj"))])
        ax.plot(range(len(configs)), ys, "o-", lw=0.8, ms=4, color=colors[i % len(colors)], label=s)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(range(len(configs)))
    ax.set_xticklabels(configs, rotation=30, ha="right", fontsize=8)
    ax.set_yscale("symlog", linthresh=10)
    ax.set_ylabel("EVU saving over HSR, frame cycles (%)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    params = {r["config"]: r.get("params", "") for r in used}
    rep.figure(fig, "crossover_params", f"The EVU's saving over HSR as one unit parameter changes ({res_name(res)}, "
               f"{spp} spp, tiles {tile}; above 0: the EVU is faster). Configurations: " +
               "; ".join(f"{c}: {params.get(c) or 'defaults'}" for c in configs), provenance(used))
    rep.para("Per scene and configuration: frame cycles of each, the EVU's saving, the share of the frame bound by "
             "memory (time a unit waited for the memory system / frame time) and DRAM traffic of each, and the "
             "saving in the energy proxy.")
    rep.table(["scene", "configuration", "cycles (EVU)", "cycles (HSR)", "EVU saving", "memory-bound (EVU)",
               "memory-bound (HSR)", "DRAM (EVU)", "DRAM (HSR)", "energy saving"], table, numeric_from=2)
    return used


def crossover_best(settings, scenes):
    """Per scene and resolution x samples with the most settings: the fastest setting of all (any EVU mode or
    hsr, tile, configuration), the fastest of the other kind, and where the EVU saves most over HSR."""
    best = {}
    for s in scenes:
        groups = defaultdict(list)
        for k, modes in settings.items():
            if k[0] == s:
                groups[(k[1], k[2])].append((k, modes))
        if not groups:
            continue
        (res, spp), cands = max(groups.items(), key=lambda g: (len(g[1]), -res_key(g[0][0])[0], g[0][1]))
        evus = [(m[mode]["cycles"], k[3], k[4], mode) for k, m in cands for mode in EVU_MODES if mode in m]
        hsrs = [(m["hsr"]["cycles"], k[3], k[4], "hsr") for k, m in cands]
        e, h = min(evus), min(hsrs)
        win = min(e, h)
        other = h if win is e else e
        widest = max(((saving(m.get("analytic"), m["hsr"]), k[3], k[4]) for k, m in cands if "analytic" in m),
                     key=lambda x: x[0])
        best[s] = {"resolution": res, "samples": spp, "settings": len(cands),
                   "best": {"cycles": win[0], "tile": win[1], "config": win[2], "mode": win[3]},
                   "runner_up_of_other_kind": {"cycles": other[0], "tile": other[1], "config": other[2],
                                               "mode": other[3]},
                   "margin": 1 - win[0] / other[0],
                   "evu_widest_saving": {"saving": widest[0], "tile": widest[1], "config": widest[2]}}
    return best


def section_crossover(rep, out, rows, scenes):
    settings = crossover_settings(rows)
    for stale in ("crossover.txt", "best_configs.json"):
        (out / stale).unlink(missing_ok=True)
    if not settings:
        return {}
    rep.heading("Crossover: where the EVU pays off against per-pixel HSR", 2, "crossover")
    rep.para("The same frame through the SystemC model twice, once with the early-visibility unit (mode analytic; "
             "hybrid adds per-pixel fallback tiles) and once with the per-pixel HSR unit (mode hsr), at the same "
             "tile size and unit configuration. Both shade the same visible fragments, so the difference is the "
             "visibility work (the EVU's grows with triangle pairs per tile, HSR's with samples × depth "
             "complexity) and the memory traffic each needs (the EVU reads silhouette edges too). Saving = 1 − "
             "EVU / HSR: above 0 the EVU is cheaper. The energy proxy multiplies DRAM bytes, shader lane-cycles, "
             "EVU tests and depth tests by per-access energies (model/top/config.h cites them).")
    used = crossover_heatmaps(rep, settings, scenes)
    used += crossover_params(rep, settings, scenes)
    best = crossover_best(settings, scenes)
    if best:
        rep.heading("Best setting per scene", 3, "crossover_best")
        rep.para("Per scene, at the resolution and sample count with the most settings in this sweep: the fastest "
                 "setting of all (mode, tile, configuration; configurations differ in area, so read the fastest "
                 "against its configuration), the fastest of the other kind (EVU or HSR) and the margin between "
                 "them, and the setting where the EVU saves most over HSR with the same tile and configuration.")
        rep.table(["scene", "resolution", "spp", "settings", "fastest", "cycles", "fastest of the other kind",
                   "cycles", "margin", "EVU's widest saving over HSR"],
                  [[s, res_name(b["resolution"]), b["samples"], b["settings"],
                    f"{b['best']['mode']}, {b['best']['tile']}, {b['best']['config']}", fmt_int(b["best"]["cycles"]),
                    f"{b['runner_up_of_other_kind']['mode']}, {b['runner_up_of_other_kind']['tile']}, "
                    f"{b['runner_up_of_other_kind']['config']}", fmt_int(b["runner_up_of_other_kind"]["cycles"]),
                    fmt_saving(b["margin"]),
                    f"{fmt_saving(b['evu_widest_saving']['saving'])} ({b['evu_widest_saving']['tile']}, "
                    f"{b['evu_widest_saving']['config']})"] for s, b in best.items()], numeric_from=1)
    wins = [(saving(m.get("analytic"), m["hsr"]), k) for k, m in settings.items() if "analytic" in m]
    ev = [w for w in wins if w[0] > 0]
    top, bottom = max(wins), min(wins)
    where = lambda k: f"{k[0]} {res_name(k[1])} {k[2]} spp tiles {k[3]} {k[4]}"  # noqa: E731
    line = (f"crossover: the EVU beats per-pixel HSR in frame cycles at {len(ev)} of {len(wins)} settings "
            f"(scene x resolution x samples x tile x configuration); its best setting {where(top[1])} "
            f"(saving {fmt_saving(top[0])}), its worst {where(bottom[1])} ({fmt_saving(bottom[0])})")
    rep.para(line[0].upper() + line[1:] + ".")
    rep.para(provenance(used), "*" + provenance(used) + "*")
    (out / "crossover.txt").write_text(line + "\n")
    (out / "best_configs.json").write_text(json.dumps(best, indent=2) + "\n")
    return best


def per_pixel_tiles(out, point):
    """Tiles the hybrid sent per pixel, from the point's stats.json (None if it has none)."""
    try:
        t = json.loads((out / point["dir"] / "stats.json").read_text())["totals"]
    except (KeyError, OSError, ValueError):
        return None
    return t.get("per_pixel_tiles")


def section_stability(rep, out, rows, scenes):
    """Where the analytic method fails: agreement with the truth, fallback and cost per scene and mode."""
    modes = ["analytic", "hybrid", "hsr", "early_z"]
    table, diff, used = [], [], []
    for scene in scenes:
        sims = {m: sim_point(rows, scene, "1920x1080", 1, "32x32", mode=m) for m in modes}
        if not sims.get("analytic") or not sims.get("hybrid"):
            continue
        hyb = sims["hybrid"]
        tiles = per_pixel_tiles(out, hyb)
        ntiles = math.ceil(int(hyb["width"]) / int(hyb["tile_w"])) * math.ceil(int(hyb["height"]) / int(hyb["tile_h"]))
        share = tiles / ntiles if tiles is not None else None
        cells = []
        for m in modes:
            p = sims.get(m)
            if p:
                used.append(p)
            agr = p.get("vs_truth_sample_agreement") if p else None
            cells += ["–" if agr is None else f"{100 * agr:.4f} %", fmt_int(p.get("cycles")) if p else "–"]
        a, h, z = sims["analytic"], sims["hybrid"], sims.get("hsr")
        table.append([scene, "–" if share is None else f"{fmt_int(tiles)} ({100 * share:.2f} %)", *cells,
                      fmt_s(h.get("frame_seconds")), f"{h.get('max_rss_mib', 0):.0f}"])
        if share is not None and a.get("vs_truth_sample_agreement") is not None and a.get("cycles"):
            diff.append((scene, share, 1 - a["vs_truth_sample_agreement"], 1 - (h.get("vs_truth_sample_agreement") or 0),
                         h["cycles"] / a["cycles"], (z["cycles"] / a["cycles"]) if z and z.get("cycles") else None))
    if not table:
        return
    rep.heading("Stability: where the analytic method fails", 2, "stability")
    rep.para("SVGPU assumes geometry that does not interpenetrate. Per scene (1080p, 1 spp, 32×32 tiles, the model at "
             "fidelity tile): agreement of each mode's id buffer with the exact z-buffer truth, the model's frame "
             "cycles, and the tiles the hybrid mode resolved per pixel (its measure of how far the scene breaks the "
             "assumption: interpenetration, non-opaque content, work over budget). Host time and peak memory are "
             "the hybrid run's.")
    head = ["scene", "hybrid tiles per pixel"]
    for m in modes:
        head += [f"agreement ({m})", f"cycles ({m})"]
    rep.table(head + ["hybrid s / frame", "hybrid peak MiB"], table, numeric_from=1)
    rep.para(provenance(used), "*" + provenance(used) + "*")
    if not diff:
        return
    fig, axes = plt.subplots(1, 2, figsize=(12.4, 4.2), squeeze=False)
    floor = 1e-7
    xs = [max(d[1], 1e-4) for d in diff]
    ax = axes[0][0]
    ax.scatter(xs, [max(d[2], floor) for d in diff], label="analytic", s=30)
    ax.scatter(xs, [max(d[3], floor) for d in diff], label="hybrid", marker="x", s=40)
    for d, x in zip(diff, xs):
        ax.annotate(d[0], (x, max(d[2], floor)), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_yscale("log")
    ax.set_xscale("log")
    ax.axhline(floor, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("difficulty: share of tiles hybrid resolves per pixel")
    ax.set_ylabel("sample disagreement with the truth")
    ax.set_title("error against difficulty (0 drawn on the dotted line)", fontsize=10)
    ax2 = axes[0][1]
    ax2.scatter(xs, [d[4] for d in diff], label="hybrid / analytic")
    ax2.scatter([x for x, d in zip(xs, diff) if d[5]], [d[5] for d in diff if d[5]], marker="x", label="hsr / analytic")
    for d, x in zip(diff, xs):
        ax2.annotate(d[0], (x, d[4]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax2.set_xscale("log")
    ax2.axhline(1.0, color="grey", lw=0.8, ls=":")
    ax2.set_xlabel("difficulty: share of tiles hybrid resolves per pixel")
    ax2.set_ylabel("frame cycles relative to analytic")
    ax2.set_title("cost against difficulty", fontsize=10)
    for a_ in (ax, ax2):
        a_.grid(alpha=0.3, which="both")
        a_.legend(fontsize=8)
    fig.tight_layout()
    rep.figure(fig, "stability", "Error and cost against scene difficulty (scenes with no tile per pixel are drawn "
               "at 1e-4)", provenance(used))


def section_configs(rep, rows):
    sims = [r for r in rows if r.get("status") == "done" and r.get("kind") == "timing"]
    configs = sorted({r["config"] for r in sims})
    if len(configs) < 2:
        return
    rep.heading("Unit configurations", 2, "configs")
    rep.para("Frame cycles of the SystemC model under each unit configuration (the -p sets of the sweep file), "
             "same scene, resolution, samples, tile, mode and fidelity.")
    keys = sorted({(r["scene"], r["resolution"], int(r["samples"]), r["tile"], r["producer"], r.get("mode", ""))
                   for r in sims}, key=lambda k: (k[0], res_key(k[1]), k[2], tile_key(k[3]), k[4], k[5]))
    table, used = [], []
    for k in keys:
        vals = []
        base = first(rows, scene=k[0], resolution=k[1], samples=k[2], tile=k[3], producer=k[4], mode=k[5],
                     config="default")
        if sum(1 for c in configs if first(rows, scene=k[0], resolution=k[1], samples=k[2], tile=k[3], producer=k[4],
                                           mode=k[5], config=c)) < 2:
            continue
        for c in configs:
            p = first(rows, scene=k[0], resolution=k[1], samples=k[2], tile=k[3], producer=k[4], mode=k[5], config=c)
            if p:
                used.append(p)
            v = p.get("cycles") if p else None
            rel = f" ({100 * (v / base['cycles'] - 1):+.1f} %)" if v and base and base.get("cycles") and c != "default" else ""
            pr = f", {fmt_int(p.get('partial_renders'))} partial renders" if p and p.get("partial_renders") else ""
            vals.append(fmt_int(v) + rel + pr if v is not None else "–")
        table.append([k[0], k[1], k[2], k[3], k[4], k[5]] + vals)
    params = {r["config"]: r.get("params", "") for r in sims}
    rep.table(["scene", "resolution", "spp", "tile", "fidelity", "mode"] +
              [f"{c} ({params.get(c) or 'defaults'})" for c in configs], table, numeric_from=6)
    rep.para(provenance(used), "*" + provenance(used) + "*")


def main():
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    out = Path(sys.argv[1]).resolve()
    manifest, raw = collect(out)
    write_csv(raw, out / "points.csv")
    rows = read_csv(out / "points.csv")
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    name = out.name
    rep = Report(out, manifest)
    title = f"TileVis sweep: {name}"
    rep.heading(title, 1)
    if manifest.get("description"):
        rep.para(manifest["description"])
    done = sum(1 for r in rows if r.get("status") == "done")
    unavailable = sum(1 for r in rows if r.get("status") == "unavailable")
    missing = sum(1 for r in rows if r.get("status") == "missing")
    rep.para(f"Sweep file {manifest.get('sweep_file', '?')}: {len(rows)} points, {done} done, {unavailable} "
             f"unavailable on this machine, {missing} not (yet) run. Data: points.csv (one row per point); every "
             "point's canonical outputs are in points/SCENE/RESOLUTION-sSAMPLES/PRODUCER/tTILE/.")
    runs = manifest.get("runs", [])
    if runs:
        rep.table(["run finished", "commit", "machine", "-j", "jobs run", "already done", "failed", "unavailable",
                   "interrupted", "wall s"],
                  [[r.get("finished", "?"), r.get("commit", "?"),
                    f"{r.get('machine', {}).get('host', '?')}: {r.get('machine', {}).get('cpu', '?')}, "
                    f"{r.get('machine', {}).get('cores', '?')} cores, {r.get('machine', {}).get('memory_gib', '?')} GiB",
                    r.get("jobs"), r.get("ran"), r.get("already_done"), r.get("failed"), r.get("unavailable"),
                    "yes" if r.get("interrupted") else "no", f"{r.get('wall_seconds', 0):.1f}"] for r in runs],
                  numeric_from=3)
    rep.html.append('<nav><a href="#savings">savings</a><a href="#tiles">tile size</a><a href="#best">best tile</a>'
                    '<a href="#heatmaps">heatmaps</a><a href="#crosscheck">cross-check</a>'
                    '<a href="#speed">speed vs accuracy</a><a href="#configs">configurations</a>'
                    '<a href="#crossover">crossover</a></nav>')
    captured, rows, scenes = captured_section.split(manifest, rows, scenes)
    section_savings(rep, rows, scenes, out)
    best = section_tiles(rep, rows, scenes)
    section_configs(rep, rows)
    section_crossover(rep, out, rows, scenes)
    section_heatmaps(rep, out, rows, scenes)
    section_crosscheck(rep, rows, manifest)
    section_stability(rep, out, rows, scenes)
    section_speed_accuracy(rep, rows)
    captured_section.section(rep, out, captured, manifest, provenance)
    rep.heading("Producers", 2, "producers")
    rep.table(["producer", "kind", "available", "command"],
              [[n, p.get("kind", ""), "yes" if p.get("available", True) else f"no: {p.get('why', '')}",
                p.get("command", "")] for n, p in manifest.get("producers", {}).items()], numeric_from=99)
    rep.write(title)
    lines = []
    for scene, b in best.items():
        if "best" in b:
            bb = b["best"]
            label = {"cycles": "fewest frame cycles", "pair_tests": "fewest pair tests", "pieces": "fewest pieces"}
            lines.append(f"{scene}: {bb['tile']} ({label[bb['metric']]}: {fmt_int(bb['value'])}, "
                         f"{b['resolution']}, {b['samples']} spp)")
    (out / "best_tiles.txt").write_text("\n".join(lines) + ("\n" if lines else ""))
    (out / "best_tiles.json").write_text(json.dumps(best, indent=2) + "\n")
    print(f"make_report: {out / 'index.html'} ({len(rep.figures)} figures, {done} points)")


if __name__ == "__main__":
    main()
