#!/bin/sh
# Captures the real workloads (issue 17): glmark2-x11's scenes and neverball's title screen
# (a level replaying behind the menu), each as a trace with the application's depth beside
# it, then compares that depth with the exact truth's and writes OUT/summary.md and
# OUT/summary.json. Made at demo time, never committed: the traces are outputs of the
# programs Debian ships (packages glmark2-x11, glmark2-data, neverball, xvfb).
# Usage: traces/capture/capture_workloads.sh OUT [TILEVIS]   (default TILEVIS: build/model/app/tilevis)
# FRAMES (default 1) and SKIP (default 5) choose the frames; SCENES overrides the scene list.
# A workload already captured (its trace and depth check in OUT) is kept: RECAPTURE=1 captures
# it again. SIMULATE=0 leaves out the runs through truth, golden and the model below: a sweep
# that names OUT as a trace set runs them (./tilevis demo: reports/sweeps/demo.json).
# glmark2 is captured with --offscreen (every render pass a trace frame: shadow maps, terrain's
# and desktop's render-to-texture passes); OFFSCREEN=0 keeps only what reaches the window.
set -u
out=${1:?usage: capture_workloads.sh OUT [TILEVIS]}
tilevis=${2:-build/model/app/tilevis}
frames=${FRAMES:-1}
skip=${SKIP:-5}
scenes=${SCENES:-"build texture shading bump effect2d pulsar desktop buffer ideas jellyfish terrain shadow refract conditionals function loop"}
mkdir -p "$out"
unset DISPLAY
failed=""
# Kept when already captured and checked (the sweep's points of it stay valid).
captured() { [ "${RECAPTURE:-0}" != 1 ] && [ -s "$out/$1.tvt" ] && [ -s "$out/$1.depth.json" ]; }
for s in $scenes; do
  echo "== glmark2 $s"
  if captured "glmark2_$s"; then echo "   already captured (RECAPTURE=1 captures it again)"; continue; fi
  offscreen=--offscreen
  [ "${OFFSCREEN:-1}" = 0 ] && offscreen=
  if "$tilevis" capture $offscreen --frames "$frames" --skip "$skip" --timeout 300 -o "$out/glmark2_$s.tvt" -- \
       glmark2 -b "$s:duration=60" > "$out/glmark2_$s.log" 2>&1; then
    tail -n 8 "$out/glmark2_$s.log" | grep -v '^\*\*\|^===\|^ *GL_\|Surface\|^\['
    "$tilevis" compare-depth "$out/glmark2_$s.tvt" -o "$out/glmark2_$s.depth.json"
  else
    echo "   not captured (see $out/glmark2_$s.log)"; failed="$failed glmark2_$s"
  fi
done
if [ -x /usr/games/neverball ]; then
  echo "== neverball (title screen)"
  if captured neverball_title; then echo "   already captured (RECAPTURE=1 captures it again)"; else
  # Frame 200: the title screen's level replay is running; no sound device under Xvfb.
  if SDL_AUDIODRIVER=dummy "$tilevis" capture --frames "$frames" --skip "${NEVERBALL_SKIP:-200}" --timeout 300 \
       -o "$out/neverball_title.tvt" -- /usr/games/neverball > "$out/neverball_title.log" 2>&1; then
    grep -v '^\*\*\|^GL ' "$out/neverball_title.log" | tail -n 4
    "$tilevis" compare-depth "$out/neverball_title.tvt" -o "$out/neverball_title.depth.json"
  else
    echo "   not captured (see $out/neverball_title.log)"; failed="$failed neverball_title"
  fi
  fi
fi
# Every trace frame through the producers: the exact truth, golden analytic and hybrid (and
# their agreement with the truth), the SystemC model at tiles 16, 32 and 64.
for t in "$out"/*.tvt; do
  [ "${SIMULATE:-1}" = 0 ] && break
  w=${t%.tvt}
  n=$("$tilevis" info "$t" --summary | sed -n 's/.* \([0-9][0-9]*\) frame(s).*/\1/p')
  k=0
  while [ "$k" -lt "${n:-0}" ]; do
    v="$w.v/f$k"
    "$tilevis" golden "$t" --frame "$k" --truth -o "$v/truth" > /dev/null &&
    "$tilevis" golden "$t" --frame "$k" -o "$v/analytic" > /dev/null &&
    "$tilevis" golden "$t" --frame "$k" --mode hybrid -o "$v/hybrid" > /dev/null &&
    "$tilevis" compare "$v/analytic" "$v/truth" -o "$v/analytic_vs_truth" > /dev/null &&
    "$tilevis" compare "$v/hybrid" "$v/truth" -o "$v/hybrid_vs_truth" > /dev/null &&
    "$tilevis" sim "$t" --frame "$k" --tile 16 -o "$v/sim_16" > /dev/null &&
    "$tilevis" sim "$t" --frame "$k" --tile 32 -o "$v/sim_32" > /dev/null &&
    "$tilevis" sim "$t" --frame "$k" --tile 64 -o "$v/sim_64" > /dev/null ||
    { echo "   $(basename "$t") frame $k: a producer failed"; failed="$failed $(basename "$w")-f$k"; }
    k=$((k + 1))
  done
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
    d = [f for f in d if not f.get("no_depth_buffer")]  # passes into framebuffers without depth
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
    r = rows[-1]
    fr = sorted(glob.glob(os.path.join(out, name + ".v", "f*")), key=lambda p: int(os.path.basename(p)[1:]))
    load = lambda v, p: json.load(open(os.path.join(v, p))) if os.path.exists(os.path.join(v, p)) else None
    ok_frames = [v for v in fr if all(load(v, p) for p in ("truth/stats.json", "analytic/stats.json", "hybrid/stats.json",
                 "analytic_vs_truth/compare.json", "hybrid_vs_truth/compare.json", "sim_16/stats.json", "sim_32/stats.json", "sim_64/stats.json"))]
    if fr and len(ok_frames) == len(fr) and os.environ.get("SIMULATE", "1") != "0":  # else the sweep runs them
        f = {"none": 0, "early_z": 0, "hsr": 0, "analytic": 0, "hybrid": 0}
        cycles = {16: 0, 32: 0, 64: 0}
        compared = {"analytic": 0, "hybrid": 0}; mismatched = {"analytic": 0, "hybrid": 0}
        pixels = 0
        for v in fr:
            m = load(v, "truth/stats.json")["modes"]
            for key in ("none", "early_z", "hsr"): f[key] += m[key]
            f["analytic"] += load(v, "analytic/stats.json")["totals"]["fragments_shaded"]
            f["hybrid"] += load(v, "hybrid/stats.json")["totals"]["fragments_shaded"]
            for mode in ("analytic", "hybrid"):
                cj = load(v, f"{mode}_vs_truth/compare.json")
                compared[mode] += cj["samples_compared"]; mismatched[mode] += cj["mismatched_samples"]
            for t in cycles: cycles[t] += load(v, f"sim_{t}/stats.json")["totals"]["cycles"]
        for p in c.get("passes", []): pixels += p["width"] * p["height"]
        if not pixels: pixels = c["viewport"][0] * c["viewport"][1] * c["frames"]
        r["trace_frames"] = len(fr)
        r["overdraw"] = f["none"] / pixels  # fragments per pixel of every pass, immediate mode
        r["non_occluding_share"] = c["non_occluding_triangles"] / c["triangles"] if c["triangles"] else 0
        r["fragments"] = f
        r["analytic_agreement"] = 1 - mismatched["analytic"] / compared["analytic"] if compared["analytic"] else 1.0
        r["hybrid_agreement"] = 1 - mismatched["hybrid"] / compared["hybrid"] if compared["hybrid"] else 1.0
        r["sim_cycles"] = cycles
        r["best_tile"] = min(cycles, key=cycles.get) if cycles else None
json.dump(rows, open(os.path.join(out, "summary.json"), "w"), indent=2)
pct = lambda v: "-" if v is None else f"{100 * v:.4f} %"
lines = ["| workload | frames | draws | triangles | non-occluding draws | draws left out | covered px | depth agreement | under the app's depth-write rule | differences |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
for r in rows:
    diff = ", ".join(f"{k} {v}" for k, v in sorted(r["differences"].items())) or "none"
    lines.append(f"| {r['workload']} | {r['frames']} | {r['draws']} | {r['triangles']:,} | {r['non_occluding_draws']} | "
                 f"{r['skipped_draws']} | {r['covered_pixels']:,} | {pct(r['agreement'])} | {pct(r['agreement_gl_rule'])} | {diff} |")
if any("fragments" in r for r in rows): lines += ["", "| workload | trace frames (passes) | non-occluding triangles | fragments per pixel | fragments none | early-Z | HSR | analytic | hybrid | analytic = truth | hybrid = truth | model cycles 16 / 32 / 64 | best tile |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|"]
for r in rows:
    if "fragments" not in r: continue
    f = r["fragments"]; c = r["sim_cycles"]
    lines.append(f"| {r['workload']} | {r['trace_frames']} | {pct(r['non_occluding_share'])} | {r['overdraw']:.2f} | {f['none']:,} | {f['early_z']:,} | {f['hsr']:,} | {f['analytic']:,} | "
                 f"{f['hybrid']:,} | {pct(r['analytic_agreement'])} | {pct(r['hybrid_agreement'])} | "
                 f"{' / '.join(f'{c[t]:,}' for t in sorted(c))} | {r['best_tile']} |")
json.dump(rows, open(os.path.join(out, "summary.json"), "w"), indent=2)
open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
[ -z "$failed" ] || echo "not captured:$failed"
