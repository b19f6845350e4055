#!/usr/bin/python3
"""How long `tilevis sweep --status` takes on a sweep of 1,000 points. Prints the figures.

  python3 model/sweep/bench_status.py --tilevis build/model/app/tilevis [--work DIR] [--runs 20]

The sweep: 5 built-in scenes x 50 tile sizes x 4 producers (golden, truth, sim_tile,
sim_analytic) = 1,000 points, 5 traces, 500 comparisons. Its folder is made without running
the producers: `--jobs-file` writes sweep.json, then 600 points get a stats.json and a
process.json (synthetic wall seconds: --status reads only these) and the traces an empty file.
Measured, as a user runs it (a tilevis process each time, wall clock):
  1. --status on the folder alone (a local sweep);
  2. where the Slurm daemons can start (as in tests/report/slurm_sweep.py): the 400 points not
     done and their comparisons submitted with --slurm --sbatch-args=--hold, so that every task
     stays queued, and --status again: squeue lists all of them and each is matched to its job.
"""
import argparse
import json
import os
import random
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "report"))
from slurm_sweep import Cluster  # noqa: E402

SCENES = ["bunny", "dragon", "teapot_stadium", "stack", "glass"]
PRODUCERS = ["golden", "truth", "sim_tile", "sim_analytic"]


def tiles():
    sizes = [8, 16, 24, 32, 48, 64, 96, 128, 192, 256]
    return [f"{w}x{h}" for w in sizes for h in sizes[:5]]  # 50


def make_sweep(work):
    sweep = {"description": "bench_status: 1,000 points", "scenes": SCENES, "resolutions": ["1920x1080"],
             "grids": [{"name": "all", "tiles": tiles(), "producers": PRODUCERS}],
             "compare": [{"a": "golden", "b": "truth"}, {"a": "sim_tile", "b": "golden"}]}
    f = work / "bench1000.json"
    f.write_text(json.dumps(sweep))
    return f


def run(cmd, env):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    dt = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"bench_status: {' '.join(map(str, cmd))} exited {p.returncode}\n{p.stderr[-2000:]}")
    return p.stdout, dt


def populate(out, done_share, seed=1):
    manifest = json.loads((out / "sweep.json").read_text())
    rng = random.Random(seed)
    for t in {p["trace"] for p in manifest["points"]}:
        (out / t).parent.mkdir(parents=True, exist_ok=True)
        (out / t).write_bytes(b"")
    points = manifest["points"]
    for p in rng.sample(points, int(len(points) * done_share)):
        d = out / p["dir"]
        d.mkdir(parents=True, exist_ok=True)
        (d / "stats.json").write_text(json.dumps({"tool": p["producer"], "totals": {}}))
        (d / "process.json").write_text(json.dumps({"command": p["command"], "wall_seconds": rng.uniform(0.5, 5.0),
                                                    "cpu_seconds": 1.0, "max_rss_mib": 100.0}))
    return len(points)


def measure(a, out, env, label):
    cmd = [a.tilevis, "sweep", str(out / "sweep-file.json"), "-o", str(out), "--status"]
    text, _ = run(cmd, env)  # warm the page cache once
    times = [run(cmd, env)[1] for _ in range(a.runs)]
    print(f"{label}: median {statistics.median(times):.3f} s, max {max(times):.3f} s over {a.runs} runs")
    return text


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tilevis", required=True)
    ap.add_argument("--work", default="/tmp/tilevis-bench-status")
    ap.add_argument("--runs", type=int, default=20)
    a = ap.parse_args()
    work = Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    out = work / "out"
    sweep = make_sweep(work)
    env = dict(os.environ)
    run([a.tilevis, "sweep", str(sweep), "-o", str(out), "--jobs-file", str(work / "jobs.sh")], env)
    shutil.copy(sweep, out / "sweep-file.json")
    n = populate(out, 0.6)
    print(f"bench_status: {n} points (600 done), {os.cpu_count()} cores, {a.tilevis}")
    print(measure(a, out, env, "--status, folder only (no Slurm)").rstrip())

    cluster = Cluster()
    try:
        why = cluster.start()
        if why:
            print(f"bench_status: Slurm part not measured: the daemons cannot start here: {why}")
            return 0
        text, dt = run([a.tilevis, "sweep", str(out / "sweep-file.json"), "-o", str(out), "--slurm",
                        "--sbatch-args=--hold"], cluster.env)
        print(f"--slurm submission took {dt:.2f} s: {text.strip().splitlines()[0]}")
        print(measure(a, out, cluster.env, "--status with every task held in squeue").rstrip())
        run([a.tilevis, "sweep", str(out / "sweep-file.json"), "-o", str(out), "--cancel"], cluster.env)
    finally:
        cluster.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
