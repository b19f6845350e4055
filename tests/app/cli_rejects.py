#!/usr/bin/env python3
"""Every corrupted input ends with a one-line error naming the place, a non-zero exit, no
signal, and under 1 GiB of memory: `tilevis info` on corrupted traces (the fuzz corpus's
bad seeds, truncations, byte flips, huge counts) and `tilevis trace` on bad scenes."""
import os
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

LIMIT = 1 << 30  # bytes: a run that needs more fails
SANITIZED = "--sanitized" in sys.argv  # an ASan build maps terabytes of shadow memory up front


def limit():
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT * 2, LIMIT * 2))  # headroom for the loader; RSS is checked below


def run(cmd):
    if SANITIZED:  # no address-space limit; ASan itself aborts on any single allocation over LIMIT
        env = dict(os.environ, ASAN_OPTIONS=f"max_allocation_size_mb={LIMIT >> 20}:allocator_may_return_null=0")
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    else:
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=limit)
    _, status, usage = os.wait4(p.pid, 0)
    err = p.stderr.read().decode(errors="replace")
    return status, err, usage.ru_maxrss * 1024


def check(name, cmd, place):
    status, err, rss = run(cmd)
    problems = []
    if os.WIFSIGNALED(status):
        problems.append(f"died of signal {os.WTERMSIG(status)}")
    elif os.WEXITSTATUS(status) == 0:
        problems.append("exit status 0")
    lines = [l for l in err.splitlines() if l.strip()]
    if len(lines) != 1:
        problems.append(f"{len(lines)} lines on stderr")
    if place and place not in err:
        problems.append(f"message does not name {place!r}")
    if rss > LIMIT:
        problems.append(f"peak RSS {rss >> 20} MiB")
    print(f"{'FAIL' if problems else 'ok  '} {name}: {err.strip()[:150]} {'; '.join(problems)}")
    return not problems


def main():
    binary, corpus = sys.argv[1], Path(sys.argv[2])  # [--sanitized]
    tmp = Path(tempfile.mkdtemp(prefix="tilevis_cli_"))
    good = max((p for p in corpus.iterdir() if p.name.startswith("valid")), key=lambda p: p.stat().st_size)
    data = good.read_bytes()
    cases = {}
    for p in sorted(corpus.iterdir()):
        if not p.name.startswith("valid"):
            cases[p.name] = p.read_bytes()
    for n in (0, 7, 8, 20, 31, len(data) // 2, len(data) - 1):
        cases[f"truncated_{n}"] = data[:n]
    for off in (0, 9, 13, 17, 25, 40, 60, 90):
        b = bytearray(data)
        b[off] ^= 0xFF
        cases[f"flip_{off}"] = bytes(b)
    cases["appended"] = data + b"\0" * 3
    cases["huge_frame_count"] = data[:24] + b"\xff\xff\xff\xff" + data[28:]
    ok = True
    for name, content in cases.items():
        f = tmp / f"{name}.tvt"
        f.write_bytes(content)
        status, _, _ = run([binary, "info", str(f)])
        if os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0:
            print(f"ok   {name}: accepted (a corruption the format cannot see, e.g. inside a float)")
            continue
        ok &= check(name, [binary, "info", str(f)], str(f))
    scenes = {
        "bad_json": '{"objects": [',
        "unknown_key": '{"objects": [], "colour": 1}',
        "bad_mesh": '{"objects": [{"mesh": "nowhere.obj"}]}',
        "bad_viewport": '{"viewport": [0, 1], "objects": []}',
        "duplicate_key": '{"viewport": [64, 32], "objects": [{"primitive": {"type": "box"}, "name": "a", "name": "b"}]}',
        "number_overflow": '{"objects": [{"primitive": {"type": "box", "size": 1e400}}]}',
    }
    for name, text in scenes.items():
        f = tmp / f"{name}.json"
        f.write_text(text)
        ok &= check(name, [binary, "trace", str(f), "-o", str(tmp / "out.tvt")], str(f))
    (tmp / "huge.obj").write_text("v 0 0 0\nv 1 0 0\nv 1e39 1 0\nf 1 2 3\n")
    (tmp / "huge_vertex.json").write_text('{"objects": [{"name": "thing", "mesh": "huge.obj", "fit": false}]}')
    ok &= check("huge_vertex", [binary, "trace", str(tmp / "huge_vertex.json"), "-q", "-o", str(tmp / "out.tvt")],
                'object "thing": vertex 2')
    configs = {
        "config_duplicate_key": ('{"sim": {"mode": "hsr", "mode": "analytic"}}', "$.sim.mode"),
        "config_two_spellings": ('{"sim.mode": "hsr", "sim": {"mode": "analytic"}}', "sim.mode is set twice"),
        "config_overflow": ('{"evu": {"reject": {"lanes": 1e400}}}', "line 1, column"),
    }
    for name, (text, place) in configs.items():
        f = tmp / f"{name}.json"
        f.write_text(text)
        ok &= check(name, [binary, "sim", str(good), "-c", str(f), "-o", str(tmp / "s")], place)
    ok &= check("config_is_directory", [binary, "sim", str(good), "-c", str(tmp), "-o", str(tmp / "s")],
                "is a directory")
    if not SANITIZED:  # under the 2 GiB address-space limit of run(): refused up front, with the estimate
        (tmp / "huge_frame.json").write_text('{"viewport": [16384, 16384], "objects": [{"primitive": {"type": "quads"}}]}')
        subprocess.run([binary, "trace", str(tmp / "huge_frame.json"), "-q", "-o", str(tmp / "huge.tvt")], check=True)
        for cmd in ("golden", "sim"):
            ok &= check(f"huge_frame_{cmd}", [binary, cmd, str(tmp / "huge.tvt"), "--tile", "4", "-o", str(tmp / "h")],
                        "needs about")
    # A mirroring transform is accepted with a warning (the winding is reversed).
    (tmp / "mirror.json").write_text('{"objects": [{"name": "m", "primitive": {"type": "box"}, '
                                     '"transform": {"scale": [-1, 1, 1]}}]}')
    p = subprocess.run([binary, "trace", str(tmp / "mirror.json"), "-q", "-o", str(tmp / "m.tvt")],
                       capture_output=True, text=True)
    warned = p.returncode == 0 and "warning" in p.stderr and "mirrors it" in p.stderr
    print(f"{'ok  ' if warned else 'FAIL'} mirror_warns: {p.stderr.strip()[:150]}")
    ok &= warned
    ok &= check("missing_trace", [binary, "info", str(tmp / "missing.tvt")], "missing.tvt")
    ok &= check("bad_tile", [binary, "golden", str(good), "--tile", "3", "-o", str(tmp / "g")], "--tile")
    ok &= check("occlusion_bin_over_tile", [binary, "golden", str(good), "--tile", "16", "--occlusion-bin", "32",
                                            "-o", str(tmp / "g")], "--occlusion-bin")
    ok &= check_compare(binary, tmp, good)
    shutil.rmtree(tmp)
    sys.exit(0 if ok else 1)


def check_compare(binary, tmp, good):
    """compare and compare --explain on results that do not belong together."""
    scene = tmp / "one_quad.json"
    scene.write_text('{"viewport": [16, 8], "objects": [{"primitive": {"type": "quads"}}]}')
    small = tmp / "small.tvt"
    subprocess.run([binary, "trace", str(scene), "-q", "-o", str(small)], check=True)
    big_res, small_res = tmp / "big_res", tmp / "small_res"
    subprocess.run([binary, "golden", str(good), "-o", str(big_res)], check=True, capture_output=True)
    subprocess.run([binary, "golden", str(small), "-o", str(small_res)], check=True, capture_output=True)
    ok = check("explain_wrong_trace", [binary, "compare", str(big_res), str(big_res), "--explain", str(small)],
               "--explain " + str(small))
    bad = tmp / "bad_tiles"
    shutil.copytree(big_res, bad)
    lines = (bad / "tiles.csv").read_text().splitlines()
    lines[1] = lines[1].rsplit(",", 1)[0] + ",12x"
    (bad / "tiles.csv").write_text("\n".join(lines) + "\n")
    ok &= check("bad_tiles_csv", [binary, "compare", str(bad), str(big_res)], "tiles.csv: line 2, field")
    no_ids = tmp / "no_ids"
    shutil.copytree(big_res, no_ids)
    (no_ids / "ids.exr").unlink()
    ok &= check("missing_ids", [binary, "compare", str(big_res), str(no_ids)], "the second result has no ids.exr")
    # Results of two different traces of the same size: compared, but with a warning.
    scene2 = tmp / "two_quads.json"
    scene2.write_text('{"viewport": [16, 8], "objects": [{"primitive": {"type": "quads", "count": 2}}]}')
    small2 = tmp / "small2.tvt"
    subprocess.run([binary, "trace", str(scene2), "-q", "-o", str(small2)], check=True)
    other = tmp / "other_res"
    subprocess.run([binary, "golden", str(small2), "-o", str(other)], check=True, capture_output=True)
    p = subprocess.run([binary, "compare", str(small_res), str(small_res), "-o", str(tmp / "c1")], capture_output=True,
                       text=True)
    same = "different traces" not in p.stderr and '"same_trace": true' in (tmp / "c1" / "compare.json").read_text()
    p = subprocess.run([binary, "compare", str(small_res), str(other), "-o", str(tmp / "c2")], capture_output=True,
                       text=True)
    warned = "different traces" in p.stderr and '"same_trace": false' in (tmp / "c2" / "compare.json").read_text()
    print(f"{'ok  ' if same and warned else 'FAIL'} compare_trace_identity: same trace quiet {same}, different traces "
          f"warned {warned}")
    return ok and same and warned


if __name__ == "__main__":
    main()
