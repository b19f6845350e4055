#!/usr/bin/python3
"""Bad sweep files end with one line naming the file, the JSON path and what was expected, a
non-zero exit, and nothing written. Then a good one written out as a jobs file marks the points
of an exclusive producer, and the Slurm options are refused where they do not belong.

  sweep_rejects.py TILEVIS
"""
import subprocess
import sys
import tempfile
from pathlib import Path

GRID = '{"name": "g", "scenes": ["dragon"], "producers": ["golden"]'
CASES = [  # (sweep file text, expected in the message)
    ('{"grids": [' + GRID + ', "tile": [8]}]}', "$.grids[0].tile: unknown member"),
    ('{"grids": [' + GRID + ', "tiles": [2]}]}', "$.grids[0].tiles[0]: expected an integer in [4, 256], got 2"),
    ('{"grids": [' + GRID + ', "tiles": ["16x512"]}]}', "$.grids[0].tiles[0]: expected a tile size"),
    ('{"grids": [' + GRID + ', "samples": [3]}]}', "$.grids[0].samples[0]: expected 1, 2, 4, 8 or 16"),
    ('{"grids": [' + GRID + ', "resolutions": ["1920"]}]}', "$.grids[0].resolutions[0]: expected a resolution"),
    ('{"grids": [{"name": "g", "scenes": ["no_such_scene"], "producers": ["golden"]}]}', "$.grids[0].scenes[0]: no scene file"),
    ('{"grids": [{"name": "g", "scenes": ["dragon"], "producers": ["gold"]}]}', '$.grids[0].producers[0]: unknown producer "gold"'),
    ('{"grids": [' + GRID + ', "configs": ["fast"]}]}', '$.grids[0].configs[0]: unknown configuration "fast"'),
    ('{"grids": [' + GRID + '}], "compare": [{"a": "golden", "b": "golden"}]}', "$.compare[0]: expected two different"),
    ('{"producers": {"p": {"command": "{tilevis} golden {trace} {x} -o {out}"}}, "grids": [' + GRID + '}]}',
     "$.producers.p.command: unknown placeholder {x}"),
    ('{"producers": {"p": {"command": "{tilevis} golden {trace} -o {out}", "exclusive": "a b"}}, "grids": [' + GRID + '}]}',
     "$.producers.p.exclusive: expected a resource name"),
    ('{"grids": [' + GRID + '}], "compare": [{"a": "golden", "b": "truth", "modes": ["hsr"]}]}',
     "$.compare[0].modes: producer golden has no {mode}"),
    ('{"grids": []}', "$.grids: expected a non-empty array"),
    ('{"grids": [' + GRID + '}]', "invalid JSON"),
    ('{"scenes": "all", "grids": [{"name": "g", "producers": ["golden"]}], "extra": 1}', "$.extra: unknown member"),
]


def main():
    binary = sys.argv[1]
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for i, (text, expected) in enumerate(CASES):
            f = Path(tmp) / f"bad{i}.json"
            f.write_text(text)
            out = Path(tmp) / f"out{i}"
            p = subprocess.run([binary, "sweep", str(f), "-o", str(out)], capture_output=True, text=True, timeout=60)
            lines = [l for l in (p.stdout + p.stderr).splitlines() if l.strip()]
            ok = p.returncode not in (0, None) and p.returncode < 128 and len(lines) == 1 \
                and str(f) in lines[0] and expected in lines[0] and not out.exists()
            print(f"{'ok  ' if ok else 'FAIL'} {expected}: exit {p.returncode}: {lines}")
            failed += not ok

        f = Path(tmp) / "exclusive.json"
        f.write_text('{"producers": {"g1": {"command": "{tilevis} golden {trace} --tile {tile} -o {out}", '
                     '"exclusive": "gpu"}}, "grids": [{"name": "g", "scenes": ["dragon"], "tiles": [16, 32], '
                     '"producers": ["golden", "g1"]}]}')
        jobs = Path(tmp) / "jobs.sh"
        p = subprocess.run([binary, "sweep", str(f), "-o", str(Path(tmp) / "ex"), "--jobs-file", str(jobs)],
                           capture_output=True, text=True, timeout=60)
        lines = jobs.read_text().splitlines() if jobs.exists() else []
        g1 = [l for l in lines if not l.startswith("#") and "/g1/" in l]
        others = [l for l in lines if not l.startswith("#") and "/golden/" in l]
        ok = p.returncode == 0 and len(g1) == 2 and all(l.endswith("# exclusive: gpu (one such job at a time, for "
                                                                    "honest timings)") for l in g1) \
            and len(others) == 2 and not any("exclusive" in l for l in others)
        print(f"{'ok  ' if ok else 'FAIL'} jobs file marks the exclusive producer's points: exit {p.returncode}, "
              f"{len(g1)} marked of {len(g1)}, {len(others)} others")
        failed += not ok
        failed += check_slurm_options(binary, Path(tmp), f)
    sys.exit(1 if failed else 0)


def check_slurm_options(binary, tmp, sweep):
    """Slurm options without --slurm, and --slurm, --status, --cancel, --jobs-file together, are
    refused before anything runs; --status on a folder never run prints counts and writes nothing."""
    failed = 0
    out = tmp / "slurm_opts"
    for extra, expected in ((["--max-array", "4"], "--max-array requires --slurm"),
                            (["--partition", "p"], "--partition requires --slurm"),
                            (["--slurm", "--status"], "excludes"),
                            (["--status", "--cancel"], "excludes"),
                            (["--slurm", "--jobs-file", str(tmp / "j.sh")], "excludes")):
        p = subprocess.run([binary, "sweep", str(sweep), "-o", str(out), *extra], capture_output=True, text=True,
                           timeout=60)
        ok = p.returncode not in (0, None) and expected in p.stderr and not out.exists()
        print(f"{'ok  ' if ok else 'FAIL'} {' '.join(extra)}: exit {p.returncode}: {p.stderr.strip()[:120]}")
        failed += not ok
    p = subprocess.run([binary, "sweep", str(sweep), "-o", str(out), "--status"], capture_output=True, text=True,
                       timeout=60)
    ok = p.returncode == 0 and "0 of 4 points done" in p.stdout and "traces 0/1 done" in p.stdout and not out.exists()
    print(f"{'ok  ' if ok else 'FAIL'} --status on a folder never run: exit {p.returncode}: {p.stdout.strip()[:160]}")
    return failed + (not ok)


if __name__ == "__main__":
    main()
