#!/bin/sh
# Captures the real workloads (issue 17): glmark2-x11's scenes and neverball's title screen
# (a level replaying behind the menu), each as a trace with the application's depth beside
# it, then compares that depth with the exact truth's and writes OUT/summary.md and
# OUT/summary.json. Made at demo time, never committed: the traces are outputs of the
# programs Debian ships (packages glmark2-x11, glmark2-data, neverball, xvfb).
# Usage: traces/capture/capture_workloads.sh OUT [TILEVIS]   (default TILEVIS: build/model/app/tilevis)
# FRAMES (default 1) and SKIP (default 5) choose the frames; SCENES overrides the scene list.
set -u
out=${1:?usage: capture_workloads.sh OUT [TILEVIS]}
tilevis=${2:-build/model/app/tilevis}
frames=${FRAMES:-1}
skip=${SKIP:-5}
scenes=${SCENES:-"build texture shading bump effect2d pulsar desktop buffer ideas jellyfish terrain shadow refract conditionals function loop"}
mkdir -p "$out"
unset DISPLAY
failed=""
for s in $scenes; do
  echo "== glmark2 $s"
  if "$tilevis" capture --frames "$frames" --skip "$skip" --timeout 300 -o "$out/glmark2_$s.tvt" -- \
       glmark2 -b "$s:duration=60" > "$out/glmark2_$s.log" 2>&1; then
    tail -n 8 "$out/glmark2_$s.log" | grep -v '^\*\*\|^===\|^ *GL_\|Surface\|^\['
    "$tilevis" compare-depth "$out/glmark2_$s.tvt" -o "$out/glmark2_$s.depth.json"
  else
    echo "   not captured (see $out/glmark2_$s.log)"; failed="$failed glmark2_$s"
  fi
done
if [ -x /usr/games/neverball ]; then
  echo "== neverball (title screen)"
  # Frame 200: the title screen's level replay is running; no sound device under Xvfb.
  if SDL_AUDIODRIVER=dummy "$tilevis" capture --frames "$frames" --skip "${NEVERBALL_SKIP:-200}" --timeout 300 \
       -o "$out/neverball_title.tvt" -- /usr/games/neverball > "$out/neverball_title.log" 2>&1; then
    grep -v '^\*\*\|^GL ' "$out/neverball_title.log" | tail -n 4
    "$tilevis" compare-depth "$out/neverball_title.tvt" -o "$out/neverball_title.depth.json"
  else
    echo "   not captured (see $out/neverball_title.log)"; failed="$failed neverball_title"
  fi
fi
# Every trace through the producers, frame 0: the exact truth, golden analytic and hybrid (and
# their agreement with the truth), the SystemC model at tiles 16, 32 and 64.
for t in "$out"/*.tvt; do
  w=${t%.tvt}
  "$tilevis" golden "$t" --truth -o "$w.v/truth" > /dev/null &&
  "$tilevis" golden "$t" -o "$w.v/analytic" > /dev/null &&
  "$tilevis" golden "$t" --mode hybrid -o "$w.v/hybrid" > /dev/null &&
  "$tilevis" compare "$w.v/analytic" "$w.v/truth" -o "$w.v/analytic_vs_truth" > /dev/null &&
  "$tilevis" compare "$w.v/hybrid" "$w.v/truth" -o "$w.v/hybrid_vs_truth" > /dev/null &&
  for tile in 16 32 64; do "$tilevis" sim "$t" --tile "$tile" -o "$w.v/sim_$tile" > /dev/null || exit 1; done ||
  { echo "   $(basename "$t"): a producer failed"; failed="$failed $(basename "$w")-producers"; }
done
python3 - "$out" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
rows = []
for cap in sorted(glob.glob(os.path.join(out, "*.tvt.capture.json"))):
    name = os.path.basename(cap)[:-len(".tvt.capture.json")]
    c = json.load(open(cap))
    dpath = os.path.join(out, name + ".depth.json")
    d = json.load(open(dpath))["frames"] if os.path.exists(dpath) else []
    cov = sum(f["covered_pixels"] for f in d); ok = sum(f["within_tolerance"] for f in d)
    gcov = sum(f["covered_pixels_gl_rule"] for f in d); gok = sum(f["within_tolerance_gl_rule"] for f in d)
    diffs = {}
    for f in d:
        for k, v in f["differences"].items(): diffs[k] = diffs.get(k, 0) + v
    rows.append({"workload": name, "frames": c["frames"], "draws": c["draws"], "triangles": c["triangles"],
                 "non_occluding_draws": c["non_occluding_draws"], "skipped_draws": sum(c["skipped_draws"].values()),
                 "skipped": c["skipped_draws"], "covered_pixels": cov,
                 "agreement": ok / cov if cov else None, "agreement_gl_rule": gok / gcov if gcov else None,
                 "differences": diffs})
    v = os.path.join(out, name + ".v")
    load = lambda p: json.load(open(os.path.join(v, p))) if os.path.exists(os.path.join(v, p)) else None
    truth, analytic, hybrid = load("truth/stats.json"), load("analytic/stats.json"), load("hybrid/stats.json")
    if truth and analytic and hybrid:
        m = truth["modes"]; cov = truth["totals"]["samples_covered"]
        r = rows[-1]
        w, h = c["viewport"]
        r["overdraw"] = m["none"] / (w * h)  # fragments per screen pixel, immediate mode
        r["non_occluding_share"] = c["non_occluding_triangles"] / c["triangles"] if c["triangles"] else 0
        r["fragments"] = {"none": m["none"], "early_z": m["early_z"], "hsr": m["hsr"],
                          "analytic": analytic["totals"]["fragments_shaded"], "hybrid": hybrid["totals"]["fragments_shaded"]}
        r["analytic_agreement"] = load("analytic_vs_truth/compare.json")["sample_agreement"]
        r["hybrid_agreement"] = load("hybrid_vs_truth/compare.json")["sample_agreement"]
        cycles = {t: load(f"sim_{t}/stats.json")["totals"]["cycles"] for t in (16, 32, 64) if load(f"sim_{t}/stats.json")}
        r["sim_cycles"] = cycles
        r["best_tile"] = min(cycles, key=cycles.get) if cycles else None
json.dump(rows, open(os.path.join(out, "summary.json"), "w"), indent=2)
pct = lambda v: "-" if v is None else f"{100 * v:.3f} %"
lines = ["| workload | frames | draws | triangles | non-occluding draws | draws left out | covered px | depth agreement | under the app's depth-write rule | differences |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
for r in rows:
    diff = ", ".join(f"{k} {v}" for k, v in sorted(r["differences"].items())) or "none"
    lines.append(f"| {r['workload']} | {r['frames']} | {r['draws']} | {r['triangles']:,} | {r['non_occluding_draws']} | "
                 f"{r['skipped_draws']} | {r['covered_pixels']:,} | {pct(r['agreement'])} | {pct(r['agreement_gl_rule'])} | {diff} |")
lines += ["", "| workload | non-occluding triangles | fragments per screen pixel | fragments none | early-Z | HSR | analytic | hybrid | analytic = truth | hybrid = truth | model cycles 16 / 32 / 64 | best tile |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|"]
for r in rows:
    if "fragments" not in r: continue
    f = r["fragments"]; c = r["sim_cycles"]
    lines.append(f"| {r['workload']} | {pct(r['non_occluding_share'])} | {r['overdraw']:.2f} | {f['none']:,} | {f['early_z']:,} | {f['hsr']:,} | {f['analytic']:,} | "
                 f"{f['hybrid']:,} | {pct(r['analytic_agreement'])} | {pct(r['hybrid_agreement'])} | "
                 f"{' / '.join(f'{c[t]:,}' for t in sorted(c))} | {r['best_tile']} |")
json.dump(rows, open(os.path.join(out, "summary.json"), "w"), indent=2)
open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
[ -z "$failed" ] || echo "not captured:$failed"
