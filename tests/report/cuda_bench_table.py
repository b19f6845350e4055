#!/usr/bin/env python3
"""cuda_ref/tools/bench_table.py on a small bench.json written here: variants side by side in
the order asked, medians over passes, the change against the first, the ratios to GL from the
committed H200 report and the count of scenes within the issue's lines; an unknown variant and a
run name without a precision refused with a message and a nonzero exit."""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

root = Path(sys.argv[1])
script = root / "cuda_ref/tools/bench_table.py"
report = root / "reports/cuda/nvidia_h200.json"
gl = {b["scene"]: b["hw_raster_ms"] for b in json.loads(report.read_text())["baselines"] if b["set"] == "1080p"}


def run(stage_clip, total):
    return {"total_ms": total, "stage_ms": {"clip": stage_clip}}


bench = {
    # hot_tile: two passes each; the median of the passes is what counts.
    "hot_tile_float_base": run(0.7, 1.40), "hot_tile_float_base_pass2": run(0.7, 1.30),
    "hot_tile_float_new": run(0.6, 1.20), "hot_tile_float_new_pass2": run(0.6, 1.00),
    "hot_tile_exact_base": run(1.4, 2.0), "hot_tile_exact_new": run(1.3, 2.2),
    # teapot_stadium: float over GL before, under after.
    "teapot_stadium_float_base": run(0.3, 1.2 * gl["teapot_stadium"]),
    "teapot_stadium_float_new": run(0.2, 0.9 * gl["teapot_stadium"]),
}
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "bench.json"
    path.write_text(json.dumps(bench))
    r = subprocess.run([sys.executable, script, path, "--variants", "new,base", "--gl", report],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith("| scene, precision | new ms (clip) | base ms (clip) | base vs new | GL ms"), lines[0]
    row = next(l for l in lines if l.startswith("| hot_tile, float |"))
    # new: median of 1.20 and 1.00 = 1.10; base: 1.35; base vs new +22.7 %.
    assert "| 1.100 (0.600) | 1.350 (0.700) | +22.7 % |" in row, row
    assert f"| {gl['hot_tile']:.3f} | {1.10 / gl['hot_tile']:.2f} | {1.35 / gl['hot_tile']:.2f} |" in row, row
    exact = next(l for l in lines if l.startswith("| hot_tile, exact |"))
    assert "| 2.200 (1.300) | 2.000 (1.400) | -9.1 % |" in exact, exact
    # The float rows come before the exact ones of a scene.
    assert lines.index(row) < lines.index(exact)
    tail = "\n".join(lines[-3:])
    hot_float_new = 1.10 / gl["hot_tile"] <= 1.0
    hot_exact_new = 2.2 / gl["hot_tile"] <= 2.0
    assert f"new: float <= 1.0x GL on {1 + hot_float_new} of 2, exact <= 2.0x GL on {int(hot_exact_new)} of 1" in tail, tail
    assert "base: float <= 1.0x GL on" in tail, tail

    r = subprocess.run([sys.executable, script, path, "--variants", "base,other"], capture_output=True, text=True)
    assert r.returncode != 0 and "no runs of variant(s) other" in r.stderr, (r.returncode, r.stderr)
    path.write_text(json.dumps({"bunny_somehow": run(0.1, 0.2)}))
    r = subprocess.run([sys.executable, script, path], capture_output=True, text=True)
    assert r.returncode != 0 and "no precision" in r.stderr, (r.returncode, r.stderr)
print("bench_table: ok")
