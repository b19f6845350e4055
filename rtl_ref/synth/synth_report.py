#!/usr/bin/env python3
"""The Markdown report of rtl_ref/synth/synth.sh from its logs (one set of files per unit and lane
count: UNIT_xLANES.{meta,time,stat,ltp,ltp_modules,log}).

Cells: the gate and flip-flop cells of yosys's internal library after ABC, summed over the
hierarchy (each module's own cells times its instances); ListRam black boxes are counted apart.
Longest path: the largest `ltp -noff` length in the .ltp file (the lane's flattened netlist and
the top, or the flat unit)."""
import argparse
import os
import re
import sys

FF = re.compile(r"^\$_(DFF|DFFE|SDFF|SDFFE|SDFFCE|ALDFF|ALDFFE|DFFSR|DFFSRE|DLATCH|DLATCHSR|SR)_")
LTP = re.compile(r"^Longest topological path in (\S+) \(length=(\d+)\)")


def clean(name):
    """$paramod$<hash>\\Name or $paramod\\Name\\P=... -> Name."""
    m = re.match(r"^\$paramod(?:\$[0-9a-f]+)?\\([^\\]+)", name)
    return m.group(1) if m else name.lstrip("\\")


def parse_stat(path):
    """{module: {type: count}} of the per-module sections, and the hierarchy section's cell count."""
    mods, cur, hier_cells, in_hier = {}, None, None, False
    for line in open(path):
        m = re.match(r"^=== (.*) ===$", line.strip())
        if m:
            in_hier = m.group(1) == "design hierarchy"
            cur = None if in_hier else mods.setdefault(m.group(1), {})
            continue
        m = re.match(r"^\s+Number of cells:\s+(\d+)", line)
        if m:
            if in_hier:
                hier_cells = int(m.group(1))
            continue
        m = re.match(r"^\s+(\S+)\s+(\d+)$", line)
        if m and cur is not None:
            cur[m.group(1)] = int(m.group(2))
    return mods, hier_cells


def parse_ltp(path):
    out = {}
    if os.path.exists(path):
        for line in open(path):
            m = LTP.match(line)
            if m:
                out[m.group(1)] = int(m.group(2))
    return out


def path_segments(path):
    """The longest path of the .ltp file: (module, start, end, [(instance, gates), ...]) with the
    gates counted by the instance of the flattened netlist they came from ('' for the module's own)."""
    best, cur = None, None
    for line in open(path):
        m = LTP.match(line)
        if m:
            cur = [m.group(1), int(m.group(2)), []]
            if best is None or cur[1] > best[1]:
                best = cur
            continue
        m = re.match(r"^\s+(\d+|ff): (\S+(?: \[\d+\])?)(?: \(via (\S+)\))?", line)
        if m and cur is not None:
            cur[2].append((m.group(1), m.group(2), m.group(3)))
    if best is None or not best[2]:
        return None
    segs = []
    for idx, _, via in best[2]:
        if idx in ("0", "ff") or via is None:
            continue
        m = re.match(r"^\$flatten\\(.+?)\.(?:\$|\\)", via)
        inst = m.group(1) if m else ""
        if segs and segs[-1][0] == inst:
            segs[-1][1] += 1
        else:
            segs.append([inst, 1])
    name = lambda n: n.lstrip("\\").replace(" [", "[")
    last = best[2][-1]
    end = f"the flip-flop `{name(last[1])}`" if last[0] == "ff" else f"`{name(last[1])}`"
    return best[0], f"`{name(best[2][0][1])}`", end, segs


def parse_time(path):
    """(wall s, cpu s, peak KB, exit status, signal line or None)."""
    lines = [l.strip() for l in open(path) if l.strip()]
    sig = next((l for l in lines if l.startswith("Command")), None)
    f = lines[-1].split()
    return float(f[0]), float(f[1]) + float(f[2]), int(f[3]), int(f[4]), sig


def totals(mods, top):
    """Per module: own gates, own flip-flops, own ListRams, children {module: n}; and the unit's
    totals (cells, flip-flops, ListRams) and instances of each module in the unit."""
    own = {}
    for name, types in mods.items():
        g = ff = lr = 0
        kids = {}
        for t, n in types.items():
            if t.startswith("$_"):
                g += n
                ff += n if FF.match(t) else 0
            elif t in mods:
                kids[t] = n
            elif clean(t) == "ListRam":
                lr += n
            else:
                raise SystemExit(f"synth_report: unknown cell type {t} in {name}")
        own[name] = (g, ff, lr, kids)
    memo = {}

    def tot(name):
        if name not in memo:
            g, ff, lr, kids = own[name]
            for k, n in kids.items():
                kg, kff, klr = tot(k)
                g, ff, lr = g + n * kg, ff + n * kff, lr + n * klr
            memo[name] = (g, ff, lr)
        return memo[name]

    inst = {top: 1}

    def walk(name, n):
        for k, c in own[name][3].items():
            inst[k] = inst.get(k, 0) + n * c
            walk(k, n * c)
    walk(top, 1)
    return own, tot(top), inst


def fmt(n):
    return f"{n:,}"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--logs", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--units", nargs="+", required=True)
    ap.add_argument("--lanes", nargs="+", type=int, required=True)
    a = ap.parse_args()

    rows, metas, breakdown = [], {}, {}
    for unit in a.units:
        for lanes in a.lanes:
            base = os.path.join(a.logs, f"{unit}_x{lanes}")
            if not os.path.exists(base + ".meta"):
                rows.append(f"| {unit} | {lanes} | not run | | | | | | | |")
                continue
            meta = dict(l.rstrip("\n").split(": ", 1) for l in open(base + ".meta") if ": " in l)
            for k, v in meta.items():
                metas.setdefault(k, {}).setdefault(v, []).append(f"{unit} ×{lanes}")
            if not os.path.exists(base + ".time") or os.path.getsize(base + ".time") == 0:
                rows.append(f"| {unit} | {lanes} | not finished (no time record: still running, or stopped) | | | | | | | |")
                continue
            wall, cpu, peak, rc, sig = parse_time(base + ".time")
            secs = lambda t: f"{t:,.0f}" if t >= 10 else f"{t:.1f}"
            abc = [int(m.group(1)) for m in re.finditer(r"^Extracted (\d+) gates", open(base + ".log", errors="replace").read(), re.M)]
            tail = f"{fmt(max(abc)) if abc else '–'} | {secs(wall)} | {secs(cpu)} | {fmt(round(peak / 1024))} |"
            if rc != 0 or sig or not os.path.exists(base + ".ltp"):
                why = sig or f"yosys exited {rc}"
                err = [l.strip() for l in open(base + ".log", errors="replace") if "ERROR" in l or "bad_alloc" in l]
                rows.append(f"| {unit} | {lanes} | not finished: {why}{'; ' + err[-1] if err else ''} | | | | {tail}")
                continue
            mods, hier_cells = parse_stat(base + ".stat")
            top = unit if unit in mods else next(iter(mods))
            own, (cells, ffs, lrs), inst = totals(mods, top)
            if hier_cells is not None and hier_cells not in (cells, cells + lrs):
                print(f"synth_report: {base}: cells {cells} (+{lrs} ListRam) against stat's {hier_cells}", file=sys.stderr)
            ltp = parse_ltp(base + ".ltp")
            rows.append(f"| {unit} | {lanes} | {fmt(cells)} | {fmt(ffs)} | {max(ltp.values())} | "
                        f"{lrs if lrs else '–'} | {tail}")
            if unit not in breakdown and meta.get("flow") == "hierarchical":
                breakdown[unit] = (lanes, own, inst, parse_ltp(base + ".ltp_modules"), ltp, top,
                                   path_segments(base + ".ltp"))

    o = []
    o.append("# Synthesis of rtl_ref's units (yosys, generic cells)\n")
    o.append("Written by `rtl_ref/synth/synth.sh` from its logs (`rtl_ref/README.md`, \"Synthesis\"); "
             "not edited by hand.\n")
    for k in ("command", "flow", "sources", "yosys", "machine", "date"):
        vals = metas.get(k, {})
        if len(vals) == 1:
            o.append(f"- {k}: `{next(iter(vals))}`" if k == "command" else f"- {k}: {next(iter(vals))}")
        else:
            o.append(f"- {k}:")
            for v, pts in vals.items():
                o.append(f"  - {f'`{v}`' if k == 'command' else v}: {', '.join(pts)}")
    o.append("")
    o.append("Cells: gate and flip-flop cells of yosys's internal library after ABC, summed over the "
             "hierarchy (each module's cells times its instances); the `ListRam` black boxes (SRAM "
             "macros: the triangle list and LANES edge banks) are counted apart. Flip-flops: one-bit "
             "`$_DFF*`/`$_SDFF*` cells. Longest path: cells on the longest path from a register or "
             "port to a register or port (`ltp -noff`) in the lane's netlist flattened after mapping "
             "(the unit's lanes share no logic), or in the whole flattened unit. Wall s: elapsed time "
             "of yosys and its ABC runs (under nice on a shared machine); CPU s: their user + system "
             "time; peak MB: the largest resident set of yosys or of any one ABC process. Largest ABC run: "
             "the most gates yosys handed to one ABC call (one module's logic).\n")
    o.append("| unit | lanes | cells | flip-flops | longest path (gates) | list RAMs | largest ABC run (gates) | wall s | CPU s | peak MB |")
    o.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    o.extend(rows)
    if breakdown:
        o.append("\n## Modules (hierarchical flow)\n")
        o.append("Each distinct module is synthesized once. Instances: in the unit at the lane count "
                 "shown (a lane's blocks scale with the lanes). Cells and flip-flops: the module's own, "
                 "its submodules excluded. Longest path: `ltp -noff` inside the module, exact for a "
                 "module without submodules; for a lane, its netlist flattened with its blocks.\n")
        o.append("| unit | module | instances | cells (own) | flip-flops (own) | longest path (gates) |")
        o.append("|---|---|---:|---:|---:|---:|")
        for unit, (lanes, own, inst, ltp_m, ltp_f, top, _) in breakdown.items():
            for name in sorted(own, key=lambda n: (n != top, -own[n][0])):
                g, ff, lr, kids = own[name]
                if name in ltp_f and name != top:
                    lp = f"{ltp_f[name]} (flattened)"
                elif not kids and name in ltp_m:
                    lp = str(ltp_m[name])
                else:
                    lp = "–"
                extra = f", {lr} ListRam" if lr else ""
                o.append(f"| {unit} ×{lanes} | {clean(name)} | {inst[name]} | {fmt(g)}{extra} | {fmt(ff)} | {lp} |")
        o.append("\nThe longest path, gate by gate, by where its gates came from: an instance of a "
                 "block (its instance path in the lane, e.g. `vert[7].u`) or the module's own logic; a path "
                 "starts at a register's output or an input port and ends at a register's input or an "
                 "output port.\n")
        for unit, (lanes, own, inst, ltp_m, ltp_f, top, segs) in breakdown.items():
            if segs is None:
                continue
            mod, start, end, parts = segs
            desc = " + ".join(f"{n} in `{i}`" if i else f"{n} in {clean(mod)}" for i, n in parts)
            o.append(f"- {unit}: {sum(n for _, n in parts)} gates in {clean(mod)}, from {start} to {end}: {desc}.")
    open(a.out, "w").write("\n".join(o) + "\n")


if __name__ == "__main__":
    main()
