#!/usr/bin/env python3
"""reports/cuda/plot_ratios.py on the committed H200 report: a PNG that decodes, with every
ratio of the report read; a file that is not a report, and a report without GL ratios, refused
with a clear message and a nonzero exit."""
import json
import subprocess
import sys
import tempfile
from pathlib import Path

root = Path(sys.argv[1])
script = root / "reports/cuda/plot_ratios.py"
report = root / "reports/cuda/nvidia_h200.json"
want = sum(1 for e in json.loads(report.read_text())["entries"] if (e.get("hw_raster_ratio") or 0) > 0)
with tempfile.TemporaryDirectory() as tmp:
    tmp = Path(tmp)
    png = tmp / "ratios.png"
    r = subprocess.run([sys.executable, script, report, "-o", png], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert f"({want} ratios)" in r.stdout, r.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    import matplotlib.image
    h, w = matplotlib.image.imread(png).shape[:2]
    assert w > 600 and h > 300, (w, h)

    bad = tmp / "bad.json"
    bad.write_text('{"scenes": []}')
    r = subprocess.run([sys.executable, script, bad, "-o", tmp / "x.png"], capture_output=True, text=True)
    assert r.returncode != 0 and "not a cuda_ref report" in r.stderr, (r.returncode, r.stderr)
    empty = tmp / "empty.json"
    empty.write_text(json.dumps({"device": "x", "entries": [{"scene": "a", "precision": "float", "set": "1080p"}]}))
    r = subprocess.run([sys.executable, script, empty, "-o", tmp / "x.png"], capture_output=True, text=True)
    assert r.returncode != 0 and "no entry has a ratio" in r.stderr, (r.returncode, r.stderr)
    assert not (tmp / "x.png").exists()
print(f"cuda_chart: {w}x{h} PNG of {want} ratios; bad inputs refused")
