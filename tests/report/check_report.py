#!/usr/bin/python3
"""The sweep report as a person would look at it: runs a tiny sweep, checks that running it
again runs nothing and that an interrupted sweep finishes only the rest, then opens
index.html in headless Chromium (Selenium and chromedriver: Debian python3-selenium,
chromium-driver) and checks that the page loads with no console errors, no network requests
and every chart image decoded; saves a screenshot (OUT/screenshot.png). The sweep includes a
workload given as a trace of two passes (made here from two built-in scenes), and the report's
captured-workloads section is recounted from the points' stats.json and compare.json.

  check_report.py --tilevis BIN --sweep tiny.json --out DIR [--chromium C] [--chromedriver D]
"""
import argparse
import base64
import json
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from trace_concat import concat  # noqa: E402


def fail(msg):
    print(f"check_report: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def run_sweep(a, extra=(), expect=0):
    cmd = [a.tilevis, "sweep", a.sweep, "-o", a.out, "-j", "2", *extra]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    sys.stderr.write(p.stderr[-3000:])
    if p.returncode != expect:
        fail(f"{' '.join(cmd)} exited {p.returncode}, expected {expect}\n{p.stdout[-2000:]}")
    return p.stderr


def ran_now(stderr):
    m = re.search(r"(\d+) already done, (\d+) run now, (\d+) failed", stderr)
    if not m:
        fail("no summary line from tilevis sweep")
    return int(m.group(1)), int(m.group(2)), int(m.group(3))


def open_in_chromium(a, page, screenshot):
    """Loads the page in headless Chromium through chromedriver (Selenium); returns its title,
    its images, the console errors and every URL it requested."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = a.chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run", "--window-size=1280,1000",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    driver = webdriver.Chrome(service=Service(executable_path=a.chromedriver), options=opts)
    try:
        driver.set_page_load_timeout(30)
        driver.get(page.as_uri())
        images = driver.execute_script(
            "return Array.from(document.images).map(i => ({src: i.getAttribute('src'), "
            "complete: i.complete, width: i.naturalWidth}))")
        metrics = driver.execute_cdp_cmd("Page.getLayoutMetrics", {})
        size = metrics.get("cssContentSize") or metrics["contentSize"]
        shot = driver.execute_cdp_cmd("Page.captureScreenshot", {
            "format": "png", "captureBeyondViewport": True,
            "clip": {"x": 0, "y": 0, "width": size["width"], "height": min(size["height"], 12000), "scale": 1}})
        Path(screenshot).write_bytes(base64.b64decode(shot["data"]))
        errors = [f"{e.get('source', '')}: {e['message']}" for e in driver.get_log("browser")
                  if e.get("level") == "SEVERE"]
        requests = []
        for e in driver.get_log("performance"):
            msg = json.loads(e["message"])["message"]
            if msg.get("method") == "Network.requestWillBeSent":
                requests.append(msg["params"]["request"]["url"])
        return driver.title, images, errors, requests
    finally:
        driver.quit()


def check_crossover(out):
    """The crossover line counts what the points say: recount from their stats.json (the
    scenes' points: a trace frame's folder, fK-WxH-sS, belongs to the captured section)."""
    scene_point = lambda p: not re.match(r"f\d+-", p.parts[-4])  # noqa: E731
    wins = total = 0
    for evu in filter(scene_point, out.glob("points/*/*/sim_tile-analytic/*/stats.json")):
        hsr = evu.parents[2] / "sim_tile-hsr" / evu.parent.name / "stats.json"
        if hsr.exists():
            total += 1
            cycles = [json.loads(p.read_text())["totals"]["cycles"] for p in (evu, hsr)]
            wins += cycles[0] < cycles[1]
    line = (out / "crossover.txt").read_text() if (out / "crossover.txt").exists() else ""
    want = f"at {wins} of {total} settings"
    if total == 0 or want not in line:
        fail(f"crossover.txt should say the EVU wins {want} (from the points' stats.json): {line!r}")
    best = json.loads((out / "best_configs.json").read_text())
    if sorted(best) != sorted({p.parts[-5] for p in filter(scene_point, out.glob("points/*/*/sim_tile-hsr/*/stats.json"))}):
        fail(f"best_configs.json should hold every scene the model ran in both modes: {sorted(best)}")
    print(f"check_report: crossover {want}")


def check_functional_cache(out):
    """The sim points of one trace, tile size and mode share a functional pass: where several do,
    each recorded it (the first, or several run at once) or replayed it, with the same answers
    (a point interrupted after its record was written replays it when resumed); a point alone
    computed it and kept nothing."""
    groups = {}
    for st in out.glob("points/*/*/sim_*-*/*/stats.json"):
        mode = st.parts[-3].split("-", 1)[1]
        tile = st.parent.name.split("-")[0]
        groups.setdefault((st.parts[-5], st.parts[-4], mode, tile), []).append(json.loads(st.read_text()))
    shared = alone = 0
    seen = set()
    for key, points in groups.items():
        how = sorted(p["functional"] for p in points)
        if len(points) == 1:
            alone += 1
            if how != ["computed"]:
                fail(f"{key}: a point alone should compute its functional pass and keep nothing, got {how}")
            continue
        shared += 1
        seen |= set(how)
        if set(how) - {"recorded", "replayed"}:
            fail(f"{key}: points sharing a functional pass should record it and replay it, got {how}")
        ids = {p["totals"]["fragments_shaded"] for p in points if p["config"]["sim"]["fidelity"] != "auto"}
        if len(ids) != 1:
            fail(f"{key}: points replaying one functional pass shade different fragments: {sorted(ids)}")
    if shared == 0 or alone == 0 or seen != {"recorded", "replayed"} or not list((out / "functional_cache").glob("*.rec")):
        fail(f"expected points sharing a functional pass and points alone, and records in {out / 'functional_cache'}: "
             f"{shared} shared, {alone} alone")
    print(f"check_report: functional pass: {shared} groups of sim points shared one, {alone} points alone")


def make_captured(a, out):
    """OUT/captured/two_pass.tvt: dragon at 160x90, then glass at 128x96, as a two-pass capture."""
    scenes = Path(a.sweep).resolve().parents[2] / "traces" / "scenes"
    parts = []
    for name, vp in (("dragon", "160x90"), ("glass", "128x96")):
        t = out / f"{name}-part.tvt"
        p = subprocess.run([a.tilevis, "trace", str(scenes / f"{name}.json"), "--viewport", vp, "-q", "-o", str(t)],
                           capture_output=True, text=True, timeout=120)
        if p.returncode:
            fail(f"tilevis trace {name}: {p.stderr[-500:]}")
        parts.append(t)
    (out / "captured").mkdir(parents=True)
    concat(out / "captured" / "two_pass.tvt", parts)


def check_captured(out):
    """The captured section's numbers (captured.json, report.md) recounted from the points."""
    got = json.loads((out / "captured.json").read_text())["workloads"] if (out / "captured.json").exists() else []
    if [w["workload"] for w in got] != ["two_pass"]:
        fail(f"captured.json should hold the workload two_pass: {[w['workload'] for w in got]}")
    w = got[0]
    frames = sorted(out.glob("points/two_pass/f*"), key=lambda d: int(d.name[1:].split("-")[0]))
    if [d.name for d in frames] != ["f0-160x90-s1", "f1-128x96-s1"]:
        fail(f"the two passes should be points at their own viewports: {[d.name for d in frames]}")
    load = lambda p: json.loads(p.read_text())  # noqa: E731
    modes = {m: sum(load(d / "truth/t32x32/stats.json")["modes"][m] for d in frames) for m in ("none", "early_z", "hsr")}
    hybrid = sum(load(d / "sim_tile-hybrid/t32x32/stats.json")["totals"]["fragments_shaded"] for d in frames)
    cycles = {t: sum(load(d / f"sim_tile-hybrid/t{t}/stats.json")["totals"]["cycles"] for d in frames)
              for t in ("16x16", "32x32")}
    best = min(cycles, key=lambda t: (cycles[t], t != "16x16"))
    mism = sum(load(d / "sim_tile-hybrid/t32x32/vs-truth/compare.json")["mismatched_samples"] for d in frames)
    pixels = 160 * 90 + 128 * 96
    want = {"fragments none": (w["fragments"]["none"], modes["none"]),
            "fragments early_z": (w["fragments"]["early_z"], modes["early_z"]),
            "fragments hsr": (w["fragments"]["hsr"], modes["hsr"]),
            "fragments hybrid": (w["fragments"]["hybrid"], hybrid),
            "overdraw": (round(w["overdraw"], 9), round(modes["none"] / pixels, 9)),
            "hybrid saving vs none": (round(w["savings"]["hybrid_vs_none"], 9), round(1 - hybrid / modes["none"], 9)),
            "best tile": (w["best_tile"]["hybrid"]["tile"], best),
            "hybrid cycles by tile": (w["best_tile"]["hybrid"]["cycles_by_tile"], cycles),
            "hybrid = truth": (w["equals_truth"]["hybrid"]["equal"], mism == 0),
            "non-occluding triangles": (w["non_occluding_triangles"], 12)}
    wrong = {k: v for k, v in want.items() if v[0] != v[1]}
    if wrong:
        fail(f"captured.json disagrees with the points (reported, recounted): {wrong}")
    md = (out / "report.md").read_text()
    row = next((l for l in md.splitlines() if l.startswith("| two_pass |")), "")
    expect = [f"{modes['none']:,}", f"{hybrid:,}", best, "yes (2 passes)" if mism == 0 else "no:"]
    if not all(f" {e}" in row for e in expect):
        fail(f"report.md's captured row should show {expect}: {row!r}")
    print(f"check_report: captured section: two_pass hybrid {hybrid:,} of {modes['none']:,} fragments, best tile "
          f"{best}, hybrid = truth: {mism == 0}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tilevis", required=True)
    ap.add_argument("--sweep", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--chromium", default="/usr/bin/chromium")
    ap.add_argument("--chromedriver", default="/usr/bin/chromedriver")
    a = ap.parse_args()
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    make_captured(a, out)
    t0 = time.time()

    # Interrupt a first run part-way, then finish it: only the remaining jobs run.
    p = subprocess.Popen([a.tilevis, "sweep", a.sweep, "-o", a.out, "-j", "2", "--no-report"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    while time.time() - t0 < 60 and len(list(out.glob("points/*/*/*/*/stats.json"))) < 6:
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    if p.returncode != 130 or "interrupted" not in err:
        fail(f"an interrupted sweep should exit 130 and say so; exit {p.returncode}: {err[-1500:]}")
    before = len(list(out.glob("points/*/*/*/*/stats.json")))
    print(f"check_report: interrupted after {before} points")
    done, ran, failed = ran_now(run_sweep(a))
    if done == 0 or ran == 0 or failed:
        fail(f"the resumed sweep should run only what was left: {done} already done, {ran} run, {failed} failed")
    done2, ran2, _ = ran_now(run_sweep(a))
    if ran2 != 0:
        fail(f"a finished sweep run again should run nothing, ran {ran2}")
    print(f"check_report: resumed: {done} already done, {ran} run; run again: {ran2} run")

    index = out / "index.html"
    if not index.exists() or not (out / "report.md").exists() or not (out / "points.csv").exists():
        fail("index.html, report.md or points.csv missing")
    text = index.read_text()
    external = re.findall(r'(?:src|href)="((?:https?:)?//[^"]*)"', text)
    if external or "<script" in text:
        fail(f"the report must be self-contained: external references {external}, scripts: {'<script' in text}")
    figures = sorted(p.name for p in (out / "figures").glob("*.png"))
    for kind in ("savings", "tiles_", "heatmap_", "speed_accuracy", "crossover", "crossover_params", "captured"):
        if not any(f.startswith(kind) for f in figures):
            fail(f"no {kind} chart in {out / 'figures'}: {figures}")

    check_crossover(out)
    check_captured(out)
    check_functional_cache(out)

    title, images, errors, requests = open_in_chromium(a, index, out / "screenshot.png")
    if errors:
        fail("console errors: " + "; ".join(errors))
    outside = [u for u in requests if not (u.startswith("file:") or u.startswith("data:"))]
    if outside:
        fail(f"the report made network requests: {outside}")
    broken = [i["src"] for i in images if not i["complete"] or i["width"] == 0]
    if broken:
        fail(f"images that did not load: {broken}")
    shown = sorted(Path(i["src"]).name for i in images)
    if shown != figures:
        fail(f"the page shows {shown}, the figures folder has {figures}")
    if not title.startswith("TileVis sweep"):
        fail(f"unexpected title {title!r}")
    shot = out / "screenshot.png"
    if not shot.exists() or shot.read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
        fail("no screenshot")
    print(f"check_report: OK: {len(images)} charts loaded, no console errors, no network; screenshot {shot} "
          f"({shot.stat().st_size} bytes); {time.time() - t0:.1f} s")


if __name__ == "__main__":
    main()
