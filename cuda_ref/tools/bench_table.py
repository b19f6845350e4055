#!/usr/bin/env python3
"""The variants of a quick_check.sh bench side by side, as a Markdown table.

    python3 cuda_ref/tools/bench_table.py BENCH.json [--variants A,B,...] [--gl REPORT.json | --gl GL.json]
                                          [--stage clip]

BENCH.json: quick_check.sh's bench.json (every run's stats.json, keyed SCENE_PRECISION[_VARIANT]
[_passN]). One row per scene and precision, one column per variant (--variants: their order, the
first the reference; else as bench.json lists them): the median over passes of the new frame (total_ms) and, in brackets, the stage given by --stage (stage_ms; default
clip); then each later variant's change against the first. --gl takes the GPU's own raster time
of each scene from a full report (reports/cuda/<device>.json, its 1080p baselines) or from
quick_check.sh's gl.json, and adds each variant's new frame over it, and a last line counting
the scenes at or below the issue's lines (float 1.0x, exact 2.0x GL).
"""
import argparse
import json
import math
import re
import sys

PRECISIONS = ("float", "exact", "hybrid_float", "hybrid_exact")


def split_key(key, scenes_known):
    """SCENE_PRECISION[_VARIANT][_passN] -> (scene, precision, variant, pass)."""
    m = re.match(r"^(.*)_pass(\d+)$", key)
    key, npass = (m.group(1), int(m.group(2))) if m else (key, 1)
    # A scene that GL times first (names may hold a precision's word), then any.
    for known in (scenes_known, None):
        for p in sorted(PRECISIONS, key=len, reverse=True):
            i = key.find("_" + p)
            while i >= 0:
                scene, rest = key[:i], key[i + 1 + len(p):]
                if (not rest or rest.startswith("_")) and (not known or scene in known):
                    return scene, p, rest[1:], npass
                i = key.find("_" + p, i + 1)
    raise ValueError(f"{key}: no precision in the run's name")


def gl_times(path):
    data = json.load(open(path))
    if isinstance(data, dict) and "baselines" in data:  # a full report
        return {b["scene"]: b["hw_raster_ms"] for b in data["baselines"]
                if b.get("set", "1080p") == "1080p" and b.get("hw_raster_ms")}
    return {scene: v["hw_raster_ms"] for scene, v in data.items()}  # quick_check's gl.json


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bench")
    ap.add_argument("--gl", help="a full report's JSON or quick_check's gl.json")
    ap.add_argument("--stage", default="clip", help="stage_ms entry shown in brackets (default clip)")
    ap.add_argument("--variants", help="comma-separated variant names in the order to show, the first the reference")
    a = ap.parse_args(argv)
    runs = json.load(open(a.bench))
    if not runs:
        sys.exit(f"{a.bench}: no runs")
    gl = gl_times(a.gl) if a.gl else {}
    if a.variants:
        variants = a.variants.split(",")
        unknown = [v for v in variants if not any(k.endswith("_" + v) or f"_{v}_pass" in k for k in runs)]
        if unknown:
            sys.exit(f"{a.bench}: no runs of variant(s) {', '.join(unknown)}")
    rows = {}
    if not a.variants:
        variants = []
    for key, st in runs.items():
        try:
            scene, p, variant, npass = split_key(key, set(gl))
        except ValueError as err:
            sys.exit(f"{a.bench}: {err}")
        if variant not in variants:
            if a.variants:
                continue
            variants.append(variant)
        rows.setdefault((scene, p), {}).setdefault(variant, []).append(st)

    def median(xs):
        xs = sorted(x for x in xs if x is not None and not math.isnan(x))
        if not xs:
            return float("nan")
        return xs[len(xs) // 2] if len(xs) % 2 else 0.5 * (xs[len(xs) // 2 - 1] + xs[len(xs) // 2])

    def frame(sts):  # the median over passes of each pass's new frame
        return median([s.get("total_ms") for s in sts])

    def stage(sts):
        return median([s.get("stage_ms", {}).get(a.stage) for s in sts])

    names = [v or "run" for v in variants]
    head = ["scene, precision"] + [f"{n} ms ({a.stage})" for n in names]
    head += [f"{n} vs {names[0]}" for n in names[1:]]
    if gl:
        head += ["GL ms"] + [f"{n} / GL" for n in names]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    met = {v: {"float": 0, "exact": 0} for v in variants}
    counted = {"float": 0, "exact": 0}
    order = {p: i for i, p in enumerate(PRECISIONS)}
    for (scene, p) in sorted(rows, key=lambda k: (k[0], order[k[1]])):
        by = rows[(scene, p)]
        cells = [f"{scene}, {p}"]
        cells += [f"{frame(by[v]):.3f} ({stage(by[v]):.3f})" if v in by else "-" for v in variants]
        base = frame(by[variants[0]]) if variants[0] in by else float("nan")
        for v in variants[1:]:
            cells.append(f"{100 * (frame(by[v]) / base - 1):+.1f} %" if v in by and base > 0 else "-")
        if gl:
            g = gl.get(scene)
            cells.append(f"{g:.3f}" if g else "-")
            for v in variants:
                r = frame(by[v]) / g if g and v in by else float("nan")
                cells.append(f"{r:.2f}" if not math.isnan(r) else "-")
                if p in counted and not math.isnan(r):
                    met[v][p] += r <= (1.0 if p == "float" else 2.0)
            if p in counted and g:
                counted[p] += 1
        print("| " + " | ".join(cells) + " |")
    if gl:
        for v, n in zip(variants, names):
            print(f"\n{n}: float <= 1.0x GL on {met[v]['float']} of {counted['float']}, "
                  f"exact <= 2.0x GL on {met[v]['exact']} of {counted['exact']}", end="")
        print()


if __name__ == "__main__":
    main(sys.argv[1:])
