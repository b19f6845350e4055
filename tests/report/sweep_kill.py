#!/usr/bin/env python3
"""A sweep killed with SIGKILL leaves no running point process, and a re-run finishes it.

    sweep_kill.py --tilevis BIN --work DIR

Starts `tilevis sweep` on a small sweep, waits until one of its jobs (a trace, a point or a
comparison) is running, SIGKILLs the sweep itself (not its process group), and checks that no
process is left whose command line names the sweep's folder. Then runs the same command
again: it must finish with every point done.
"""
import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path


def jobs_of(out):
    """PIDs of processes (other than ours) whose command line mentions `out`."""
    pids = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit() or int(d.name) == os.getpid():
            continue
        try:
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if str(out) in cmd and "sweep_kill.py" not in cmd:
            pids.append((int(d.name), cmd.strip()))
    return pids


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tilevis", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    work = Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    sweep = work / "kill.json"
    sweep.write_text(json.dumps({
        "description": "sweep_kill.py: enough work that jobs are running when the sweep is killed",
        "scenes": ["dragon", "teapot_stadium"], "resolutions": ["640x360"],
        "grids": [{"name": "g", "tiles": [8, 16, 32, 64], "producers": ["golden", "truth", "sim_tile"]}],
        "compare": [{"a": "golden", "b": "truth"}]}))
    out = work / "out"
    cmd = [a.tilevis, "sweep", str(sweep), "-o", str(out), "-j", "2"]
    env = dict(os.environ)
    parent = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    # One look at /proc decides: a second look could miss a job that finished in between.
    deadline = time.time() + 60
    children = []
    while time.time() < deadline and parent.poll() is None:
        children = [p for p in jobs_of(out) if p[0] != parent.pid]
        if children:
            break
        time.sleep(0.02)
    if not children:
        parent.kill()
        sys.exit("sweep_kill: no job of the sweep seen running within 60 s (sweep exit status "
                 f"{parent.poll()})")
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    time.sleep(0.3)  # the kernel delivers the death signal at once; a job takes seconds
    left = jobs_of(out)
    if left:
        for pid, _ in left:
            os.kill(pid, signal.SIGKILL)
        sys.exit(f"sweep_kill: {len(left)} process(es) outlived the killed sweep: "
                 + "; ".join(c for _, c in left))
    print(f"killed the sweep while {len(children)} job(s) ran; none outlived it")
    rerun = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    if rerun.returncode != 0:
        sys.exit(f"sweep_kill: the re-run failed ({rerun.returncode}):\n{rerun.stdout}\n{rerun.stderr}")
    points = [l for l in (out / "points.csv").read_text().splitlines()[1:] if l]
    not_done = [l for l in points if ",done," not in l and ",unavailable," not in l]
    if not points or not_done:
        sys.exit(f"sweep_kill: after the re-run {len(not_done)} of {len(points)} points are not done")
    print(f"the re-run finished: {len(points)} points")


if __name__ == "__main__":
    main()
