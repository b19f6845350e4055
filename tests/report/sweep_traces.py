#!/usr/bin/python3
"""Workloads given to a sweep as trace files (captured programs, "traces" in a sweep file):

- a trace of two frames (two passes at different viewports: dragon at 320x180, glass at
  192x128, joined as a multi-pass capture is) and a one-frame trace, through truth and the
  model: one point per frame, each at its frame's viewport, whose stats.json totals equal
  `tilevis sim` / `tilevis golden --truth` run by hand on that frame (and frame 1's equal the
  glass trace's own frame 0: the frame really is the one asked for); comparisons pair frame
  with frame; sweep.json records each frame's triangles and non-occluding triangles as
  `tilevis info` lists them;
- an optional trace set that is missing is said on stderr (what is left out, how to make it),
  recorded in sweep.json and in the report, and does not stop the sweep;
- a missing required trace, an unreadable one, a grid of traces with resolutions, an unknown
  trace set and a producer without {frame} on a trace of two frames are each refused with one
  line naming the file and the JSON path, nothing written.

  sweep_traces.py --tilevis BIN --source SOURCE_DIR --work DIR
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from trace_concat import concat  # noqa: E402

failures = []


def check(ok, what):
    print(f"{'ok  ' if ok else 'FAIL'} {what}")
    if not ok:
        failures.append(what)


def run(cmd, **kw):
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=240, **kw)


def totals(stats_file):
    """A stats.json's totals without host timings (the only part that may differ run to run)."""
    t = json.loads(Path(stats_file).read_text())["totals"]
    return {k: v for k, v in t.items() if "seconds" not in k and not k.endswith("_ms")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tilevis", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    tv, work = a.tilevis, Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    (work / "captured").mkdir(parents=True)
    scenes = Path(a.source) / "traces" / "scenes"
    for name, vp in (("dragon", "320x180"), ("glass", "192x128")):
        p = run([tv, "trace", scenes / f"{name}.json", "--viewport", vp, "-q", "-o", work / f"{name}.tvt"])
        if p.returncode:
            raise SystemExit(f"tilevis trace {name} failed: {p.stderr}")
    two = work / "captured" / "two_pass.tvt"
    concat(two, [work / "dragon.tvt", work / "glass.tvt"])
    shutil.copy(work / "glass.tvt", work / "captured" / "one_pass.tvt")

    sweep = work / "traces.json"
    sweep.write_text(json.dumps({
        "traces": {"cap": {"path": "captured", "make": "make_them.sh {out}/x"},
                   "later": {"path": "{out}/not_yet", "optional": True, "make": "capture_them.sh {out}/not_yet"}},
        "grids": [{"name": "cap", "traces": ["cap", "later"], "tiles": [16, 32], "producers": ["truth", "sim_tile"],
                   "modes": ["analytic", "hybrid"]}],
        "compare": [{"a": "sim_tile", "b": "truth"}]}))
    out = work / "out"
    p = run([tv, "sweep", sweep, "-o", out, "-j", "2"])
    print(p.stderr[-1500:])
    check(p.returncode == 0, f"the sweep of traces exits 0 (exit {p.returncode})")
    said = [l for l in p.stderr.splitlines() if 'traces "later"' in l]
    check(len(said) == 1 and "missing" in said[0] and "left out" in said[0] and f"capture_them.sh {out}/not_yet" in said[0]
          and "grids cap" in said[0], f"the missing optional set is said with how to make it: {said}")
    m = json.loads((out / "sweep.json").read_text())
    check(m["trace_sets"]["later"]["missing"] != "" and m["trace_sets"]["cap"]["workloads"] == ["one_pass", "two_pass"],
          "sweep.json records the missing set and the workloads found")

    # One point per frame, at the frame's viewport.
    dirs = {pt["dir"] for pt in m["points"]}
    want = {f"points/two_pass/f0-320x180-s1/truth/t{t}x{t}" for t in (16, 32)} | \
        {f"points/two_pass/f1-192x128-s1/sim_tile-hybrid/t{t}x{t}" for t in (16, 32)} | \
        {"points/one_pass/f0-192x128-s1/sim_tile-analytic/t16x16"}
    check(want <= dirs and len(dirs) == 3 * 2 * 3, f"points per frame at each frame's viewport ({len(dirs)} points)")
    fr = m["workloads"]["two_pass"]["frames"]
    check([f["triangles"] for f in fr] == [19994, 70638] and [f["non_occluding_triangles"] for f in fr] == [0, 12]
          and [f["per_pixel_triangles"] for f in fr] == [0, 960],
          f"per-frame triangles, non-occluding and per-pixel triangles as tilevis info lists them: {fr}")

    # The sweep's points equal the commands run by hand on the same frame.
    by_hand = work / "by_hand"
    cases = [(["sim", two, "--frame", "1", "--tile", "16", "-p", "sim.mode=hybrid", "-p", "sim.fidelity=tile"],
              "two_pass/f1-192x128-s1/sim_tile-hybrid/t16x16"),
             (["sim", two, "--frame", "0", "--tile", "32", "-p", "sim.mode=analytic", "-p", "sim.fidelity=tile"],
              "two_pass/f0-320x180-s1/sim_tile-analytic/t32x32"),
             (["golden", two, "--frame", "1", "--truth"], "two_pass/f1-192x128-s1/truth/t32x32"),
             (["sim", work / "glass.tvt", "--tile", "16", "-p", "sim.mode=hybrid", "-p", "sim.fidelity=tile"],
              "two_pass/f1-192x128-s1/sim_tile-hybrid/t16x16")]
    for i, (cmd, point) in enumerate(cases):
        d = by_hand / str(i)
        r = run([tv, *cmd, "-o", d])
        same = r.returncode == 0 and totals(d / "stats.json") == totals(out / "points" / point / "stats.json")
        check(same, f"points/{point} equals `tilevis {' '.join(str(c) for c in cmd[:1] + cmd[2:])}`"
              + ("" if r.returncode == 0 else f" (exit {r.returncode}: {r.stderr[-300:]})"))
    # Two jobs at a time share the CPUs' host threads (unless TILEVIS_THREADS says otherwise).
    threads = int(os.environ["TILEVIS_THREADS"]) if os.environ.get("TILEVIS_THREADS", "").isdigit() \
        else max(1, len(os.sched_getaffinity(0)) // 2)
    used = {json.loads((out / pt["dir"] / "stats.json").read_text()).get("host_threads")
            for pt in m["points"] if "/sim_tile-" in pt["dir"]}
    check(used == {threads}, f"every sim point ran on {threads} host threads, its share of the CPUs: {used}")
    f0 = totals(out / "points/two_pass/f0-320x180-s1/sim_tile-hybrid/t16x16/stats.json")
    f1 = totals(out / "points/two_pass/f1-192x128-s1/sim_tile-hybrid/t16x16/stats.json")
    check(f0["triangles_in"] != f1["triangles_in"], "frames 0 and 1 are different points")

    # Comparisons pair frame with frame.
    for f, res in ((0, "320x180"), (1, "192x128")):
        c = out / f"points/two_pass/f{f}-{res}-s1/sim_tile-hybrid/t32x32/vs-truth/compare.json"
        cj = json.loads(c.read_text()) if c.exists() else {}
        check(cj.get("same_trace", False) is True and cj.get("samples_compared", 0) > 0,
              f"frame {f}'s hybrid point is compared with frame {f}'s truth: {c.name} {cj.get('same_trace')}")

    # The report says what was left out.
    md = (out / "report.md").read_text() if (out / "report.md").exists() else ""
    check("## Captured workloads" in md and "Trace set later" in md and "capture_them.sh" in md,
          "the report's captured section names the missing set and how to make it")

    # Refusals: one line naming the file and the JSON path; nothing written.
    (work / "bad").mkdir()
    (work / "bad" / "broken.tvt").write_bytes(b"\x89TVT\r\n\x1a\n" + b"\0" * 40)
    grid = '{"name": "g", "traces": ["t"], "producers": ["truth"]'
    cases = [
        ('{"traces": {"t": {"path": "nothing_here.tvt", "make": "capture_workloads.sh OUT"}}, "grids": [' + grid + '}]}',
         ["$.traces.t.path", "no trace file or folder", "make them with: capture_workloads.sh OUT"]),
        ('{"traces": {"t": {"path": "bad"}}, "grids": [' + grid + '}]}',
         ["$.traces.t.path", "not a valid trace", "broken.tvt"]),
        ('{"traces": {"t": {"path": "captured"}}, "grids": [' + grid + ', "resolutions": ["320x180"]}]}',
         ["$.grids[0].resolutions", "expected no resolutions in a grid of traces"]),
        ('{"traces": {"t": {"path": "captured"}}, "grids": [{"name": "g", "traces": ["u"], "producers": ["truth"]}]}',
         ['$.grids[0].traces[0]', 'unknown trace set "u"']),
        ('{"traces": {"t": {"path": "captured"}}, "producers": {"p": {"command": "{tilevis} golden {trace} -o {out}"}}, '
         '"grids": [{"name": "g", "traces": ["t"], "producers": ["p"]}]}',
         ["$.grids[0].producers", "producer p has no {frame}", "two_pass.tvt"]),
    ]
    for i, (text, expected) in enumerate(cases):
        f = work / f"bad{i}.json"
        f.write_text(text)
        o = work / f"bad_out{i}"
        r = run([tv, "sweep", f, "-o", o])
        lines = [l for l in (r.stdout + r.stderr).splitlines() if l.strip()]
        ok = r.returncode not in (0, None) and r.returncode < 128 and len(lines) == 1 and str(f) in lines[0] \
            and all(e in lines[0] for e in expected) and not o.exists()
        check(ok, f"refused: {expected[-1]}: exit {r.returncode}: {lines}")

    if failures:
        print(f"sweep_traces: {len(failures)} FAILED", file=sys.stderr)
        sys.exit(1)
    print("sweep_traces: PASS")


if __name__ == "__main__":
    main()
