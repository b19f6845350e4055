#!/usr/bin/python3
"""A sweep through a real single-node Slurm on localhost, against the same sweep run locally.

    slurm_sweep.py --tilevis BIN --sweep slurm_small.json --work DIR

Brings up munged, slurmctld and slurmd (Debian: munge, slurmctld, slurmd, slurm-client) in the
foreground with a generated slurm.conf in a temporary directory, then:
  1. runs the sweep locally (tilevis sweep ... -j 2);
  2. submits it with --slurm --max-array 1 (a local run into the same folder, or a second
     submission, is then refused), waits (polling --status) until a few points are done,
     cancels it with --cancel, and checks that some points are done and some are not;
  3. submits the same command again: it must submit only the jobs not done (the points done
     before the cancel keep their files untouched) and finish the sweep and its report;
  4. checks that every point has the local run's outputs and process.json keys, that
     points.csv equals the local one apart from timing columns, and report.md apart from
     timing figures and the run history.
Exit status 77 (CTest's SKIP_RETURN_CODE) only when Slurm or munge is not installed or the
daemons do not come up; the reason is printed.
"""
import argparse
import csv
import io
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SKIP = 77
DAEMONS = ("munged", "slurmctld", "slurmd")
CLIENTS = ("sbatch", "squeue", "scancel", "sinfo", "scontrol")


def fail(msg):
    print(f"slurm_sweep: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster:
    """munged + slurmctld + slurmd on this machine, stopped by the PIDs started here."""

    def __init__(self):
        self.dir = Path(tempfile.mkdtemp(prefix="tilevis-slurm-"))
        self.procs = []
        # The commit recorded with each point is pinned: a commit landing in the working tree
        # between the local run and the Slurm run is not a difference between the runners.
        self.env = dict(os.environ, SLURM_CONF=str(self.dir / "slurm.conf"),
                        TILEVIS_COMMIT=os.environ.get("TILEVIS_COMMIT", "slurm-test"))

    def start(self):
        """Returns None when the node is up, else why it is not."""
        missing = [t for t in DAEMONS + CLIENTS if not shutil.which(t, path=os.environ["PATH"] + ":/usr/sbin:/sbin")]
        if missing:
            return f"not installed: {', '.join(missing)} (Debian packages munge, slurmctld, slurmd, slurm-client)"
        sbin = lambda t: shutil.which(t, path=os.environ["PATH"] + ":/usr/sbin:/sbin")
        d = self.dir
        (d / "munge").mkdir(mode=0o700)
        key = d / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o400)
        sock = d / "munge" / "munge.socket"
        self.spawn([sbin("munged"), "-F", "-f", f"--key-file={key}", f"--socket={sock}",
                    f"--pid-file={d}/munge/munged.pid", f"--log-file={d}/munge/munged.log",
                    f"--seed-file={d}/munge/munged.seed"], d / "munged.out")
        if not self.wait(lambda: sock.exists(), 10):
            return "munged did not start: " + self.tail(d / "munged.out", d / "munge" / "munged.log")
        self.write_conf(sock)
        self.spawn([sbin("slurmctld"), "-D", "-c", "-f", str(d / "slurm.conf")], d / "slurmctld.out")
        time.sleep(1)
        self.spawn([sbin("slurmd"), "-D", "-f", str(d / "slurm.conf")], d / "slurmd.out")
        if not self.wait(lambda: self.node_state() in ("idle", "mixed", "allocated"), 40):
            return (f"the node did not come up (sinfo says {self.node_state() or 'nothing'}): "
                    + self.tail(d / "slurmctld.log", d / "slurmd.log", d / "slurmctld.out", d / "slurmd.out"))
        return None

    def write_conf(self, sock):
        d, host = self.dir, socket.gethostname().split(".")[0]
        user = "root" if os.geteuid() == 0 else os.environ.get("USER", "nobody")
        for sub in ("state", "spool"):
            (d / sub).mkdir()
        # One count-only "gpu": the sweep's exclusive-resource path (--gres=gpu:1) needs one.
        (d / "gres.conf").write_text(f"NodeName={host} Name=gpu Count=1 File=/dev/null\n")
        (d / "slurm.conf").write_text(f"""ClusterName=tilevistest
SlurmctldHost={host}(127.0.0.1)
SlurmUser={user}
SlurmdUser={user}
AuthType=auth/munge
AuthInfo=socket={sock}
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
SchedulerParameters=sched_interval=2
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
ReturnToService=2
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldLogFile={d}/slurmctld.log
SlurmdLogFile={d}/slurmd.log
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
GresTypes=gpu
NodeName={host} NodeAddr=127.0.0.1 CPUs={os.cpu_count()} Gres=gpu:1 State=UNKNOWN
PartitionName=tilevis Nodes={host} Default=YES MaxTime=INFINITE State=UP
""")

    def spawn(self, argv, log):
        self.procs.append(subprocess.Popen(argv, stdout=open(log, "w"), stderr=subprocess.STDOUT, env=self.env,
                                           stdin=subprocess.DEVNULL))

    def node_state(self):
        p = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True, env=self.env, timeout=20)
        return p.stdout.strip().rstrip("*") if p.returncode == 0 else ""

    def wait(self, ready, seconds):
        end = time.time() + seconds
        while time.time() < end:
            if any(p.poll() is not None for p in self.procs):
                return False
            if ready():
                return True
            time.sleep(0.5)
        return False

    def tail(self, *files):
        out = []
        for f in files:
            if Path(f).exists():
                lines = [l for l in Path(f).read_text(errors="replace").splitlines() if l.strip()]
                out.append(f"{Path(f).name}: " + " | ".join(lines[-3:]))
        return "; ".join(out) or "no log"

    def stop(self):
        # Jobs first: slurmd leaves a job's slurmstepd behind when it stops while the job runs.
        if len(self.procs) == 3 and all(p.poll() is None for p in self.procs):
            subprocess.run(["scancel", "--partition=tilevis"], env=self.env, capture_output=True, timeout=30)
            self.wait(lambda: not subprocess.run(["squeue", "-h"], env=self.env, capture_output=True, text=True,
                                                 timeout=20).stdout.strip(), 20)
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in reversed(self.procs):
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        shutil.rmtree(self.dir, ignore_errors=True)


def tilevis(a, env, out, *extra, expect=0):
    cmd = [a.tilevis, "sweep", a.sweep, "-o", str(out), *extra]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    if p.returncode != expect:
        fail(f"{' '.join(cmd)} exited {p.returncode}, expected {expect}\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
    return p.stdout + p.stderr, time.time() - t0


def status(a, env, out):
    text, seconds = tilevis(a, env, out, "--status")
    m = re.search(r"(\d+) of (\d+) points done", text)
    queue = [tuple(map(int, q)) for q in re.findall(r"(\d+) running, (\d+) queued", text)]
    if not m or len(queue) != 3:
        fail(f"--status printed no counts:\n{text}")
    in_queue = sum(r + q for r, q in queue) + bool(re.search(r"report: job \d+ (running|queued)", text))
    return int(m.group(1)), int(m.group(2)), in_queue, text, seconds


def wait_until(what, check, seconds):
    end = time.time() + seconds
    while time.time() < end:
        if check():
            return
        time.sleep(1)
    fail(f"timed out after {seconds} s waiting for {what}")


# points.csv's timing columns: wall, CPU and host seconds, peak memory, when it finished.
TIMING = re.compile(r"seconds|_ms$|^finished$|^max_rss_mib$")


def csv_without_timing(path):
    rows = list(csv.DictReader(open(path)))
    cols = [c for c in (rows[0].keys() if rows else []) if not TIMING.search(c)]
    return cols, sorted(tuple(r[c] for c in cols) for r in rows)


def report_without_timing(path):
    """report.md without the run-history table (when, where and how each run ran: one row per
    run, so a cancelled and resubmitted sweep has other rows than a local one)."""
    lines, out, skip = Path(path).read_text().splitlines(), [], False
    for line in lines:
        if line.startswith("| run finished"):
            skip = True
        if skip and not line.startswith("|"):
            skip = False
        if skip:
            continue
        out.append(line)
    return out


def timing_columns(header):
    """Columns of a report table that hold times or memory ("median s / frame", "wall s", "ms", "MiB")."""
    return [i for i, h in enumerate(header) if re.search(r"(^| )(s|ms|MiB)( |$)|seconds|wall", h.strip())]


MASKED = set()


def mask_tables(lines):
    """In every table, the cells of timing columns become T."""
    out, cols = [], None
    for line in lines:
        if not line.startswith("|"):
            cols = None
            out.append(line)
            continue
        cells = line.strip("|").split("|")
        if cols is None:
            cols = timing_columns(cells)
            MASKED.update(cells[i].strip() for i in cols)
        elif not set(line) <= set("|-: "):
            cells = ["T" if i in cols else c for i, c in enumerate(cells)]
        out.append("|" + "|".join(cells) + "|")
    return out


def compare_results(local, slurm):
    for name in ("points.csv",):
        lc, lr = csv_without_timing(local / name)
        sc, sr = csv_without_timing(slurm / name)
        if lc != sc or lr != sr:
            diff = [(x, y) for x, y in zip(lr, sr) if x != y][:3]
            fail(f"{name} differs apart from timing columns: columns {lc == sc}, first rows that differ {diff}")
    lm = mask_tables(report_without_timing(local / "report.md"))
    sm = mask_tables(report_without_timing(slurm / "report.md"))
    if lm != sm:
        diff = [(x, y) for x, y in zip(lm, sm) if x != y][:5]
        fail(f"report.md differs apart from timings: {len(lm)} vs {len(sm)} lines; first differences {diff}")
    print(f"slurm_sweep: points.csv ({len(lr)} rows, {len(lc)} columns besides timing) and report.md "
          f"({len(lm)} lines besides the run history; timing columns {sorted(MASKED)}) equal the local run's")


def check_points(local, slurm):
    manifest = json.loads((local / "sweep.json").read_text())
    for p in manifest["points"]:
        for side in (local, slurm):
            if not (side / p["dir"] / "stats.json").is_file():
                fail(f"{side / p['dir']}: no stats.json")
        lf = sorted(f.name for f in (local / p["dir"]).iterdir() if f.is_file())
        sf = sorted(f.name for f in (slurm / p["dir"]).iterdir() if f.is_file())
        if lf != sf:
            fail(f"{p['dir']}: files {sf} under Slurm, {lf} locally")
        lp = json.loads((local / p["dir"] / "process.json").read_text())
        sp = json.loads((slurm / p["dir"] / "process.json").read_text())
        if sorted(lp) != sorted(sp) or lp["command"] != sp["command"].replace(str(slurm), str(local)):
            fail(f"{p['dir']}: process.json differs: {sp} vs {lp}")
    return len(manifest["points"])


def run(a, cluster, work):
    env = cluster.env
    local, slurm = work / "local" / "small", work / "slurm" / "small"  # the report's title names the folder
    _, local_s = tilevis(a, env, local, "-j", "2")
    print(f"slurm_sweep: local run {local_s:.1f} s")

    t0 = time.time()
    text, _ = tilevis(a, env, slurm, "--slurm", "--max-array", "1")
    print(text.strip())
    gpu = [x for x in json.loads((slurm / "sweep.json").read_text())["slurm"]["submissions"][0]["arrays"]
           if x["resource"] == "gpu"]
    job = subprocess.run(["scontrol", "show", "job", gpu[0]["id"]] if gpu else ["true"], capture_output=True,
                         text=True, env=env).stdout
    if len(gpu) != 1 or gpu[0]["tasks"] != 4 or "gpu:1" not in job:
        fail(f"golden_gpu's points should be one array of 4 tasks asking --gres=gpu:1: {gpu}\n{job}")
    text, _ = tilevis(a, env, slurm, "-j", "1", expect=1)
    if "still queued or running" not in text:
        fail(f"a local run into a folder whose Slurm jobs are queued should be refused:\n{text}")
    text, _ = tilevis(a, env, slurm, "--slurm", expect=1)
    if "still queued or running" not in text:
        fail(f"a second submission while the first is queued should be refused:\n{text}")
    wait_until("two points done under Slurm", lambda: status(a, env, slurm)[0] >= 2, 120)
    text, _ = tilevis(a, env, slurm, "--cancel")
    print(text.strip())
    wait_until("the cancelled jobs to leave the queue", lambda: status(a, env, slurm)[2] == 0, 60)
    done, total, _, text, _ = status(a, env, slurm)
    print(text.strip())
    if not 0 < done < total:
        fail(f"after the cancel {done} of {total} points are done: expected some but not all "
             "(the cancel came too late or nothing ran)")
    before = {p: p.stat().st_mtime_ns for p in slurm.glob("points/**/stats.json")}

    text, _ = tilevis(a, env, slurm, "--slurm")
    print(text.strip())
    m = re.search(r"submission 2 to Slurm: (\d+) of (\d+) jobs \((\d+) already done\)", text)
    if not m or int(m.group(1)) + int(m.group(3)) != int(m.group(2)) or int(m.group(3)) < done:
        fail(f"the second submission should send only what is not done:\n{text}")
    wait_until("the sweep and its report to finish",
               lambda: status(a, env, slurm)[2] == 0 and (slurm / "report.md").exists(), 240)
    slurm_s = time.time() - t0
    done, total, _, text, status_s = status(a, env, slurm)
    print(text.strip())
    print(f"slurm_sweep: --status answered in {status_s:.2f} s (tilevis process, squeue included)")
    if done != total:
        fail(f"{done} of {total} points done after the second submission")
    after = {p: p.stat().st_mtime_ns for p in before}
    if after != before:
        fail("points done before the cancel were run again")
    subs = json.loads((slurm / "sweep.json").read_text())["slurm"]["submissions"]
    if len(subs) != 2 or not all(s["arrays"] and s["report"] for s in subs):
        fail(f"sweep.json should hold two submissions with their job ids: {subs}")
    n = check_points(local, slurm)
    compare_results(local, slurm)
    print(f"slurm_sweep: {n} points; Slurm part (submit, cancel, resubmit, report) {slurm_s:.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tilevis", required=True)
    ap.add_argument("--sweep", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    work = Path(a.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    t0 = time.time()
    cluster = Cluster()
    try:
        why = cluster.start()
        if why:
            print(f"slurm_sweep: SKIP: the Slurm daemons cannot start here: {why}")
            return SKIP
        print(f"slurm_sweep: munged, slurmctld and slurmd up in {time.time() - t0:.1f} s")
        run(a, cluster, work)
    finally:
        cluster.stop()
    print(f"slurm_sweep: passed in {time.time() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
