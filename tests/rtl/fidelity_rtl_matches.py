#!/usr/bin/env python3
"""Fidelity rtl against primitive on one scene: the early-visibility unit's clocks per tile
(tiles.csv cycles_evu_reject, _clip, _occlude) and the frame's cycles. The cost functions of
model/units/early_visibility_unit have the RTL's shape and defaults, so with the Verilated EVU
behind fidelity rtl the two must agree tile for tile; a difference names the tile and unit.

  fidelity_rtl_matches.py TILEVIS SCENE.json WORKDIR [-p key=value ...]
"""
import csv
import json
import subprocess
import sys
from pathlib import Path


def main():
    tilevis, scene, work = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    extra = sys.argv[4:]
    work.mkdir(parents=True, exist_ok=True)
    trace = work / f"{scene.stem}.tvt"
    subprocess.run([tilevis, "trace", str(scene), "-q", "-o", str(trace)], check=True)
    runs = {}
    for level in ("primitive", "rtl"):
        out = work / f"{scene.stem}_{level}"
        subprocess.run([tilevis, "sim", str(trace), "-p", f"sim.fidelity={level}", *extra, "-o", str(out)], check=True,
                       stdout=subprocess.DEVNULL)
        stats = json.loads((out / "stats.json").read_text())
        runs[level] = (list(csv.DictReader(open(out / "tiles.csv"))), stats["totals"]["cycles"], stats["host_seconds"])
        # The host seconds' split: the Verilated EVU's time is counted at rtl and only there,
        # apart from the functional model's.
        rtl_s, functional_s = stats["host_rtl_seconds"], stats["host_functional_seconds"]
        if (rtl_s > 0) != (level == "rtl") or not 0 < functional_s <= stats["host_seconds"] - rtl_s:
            print(f"FAILED: {level}: host_rtl_seconds {rtl_s}, host_functional_seconds {functional_s}, "
                  f"host_seconds {stats['host_seconds']}")
            return 1
    (prim, prim_cycles, prim_s), (rtl, rtl_cycles, rtl_s) = runs["primitive"], runs["rtl"]
    cols = ["cycles_evu_reject", "cycles_evu_clip", "cycles_evu_occlude"]
    bad = [(r["tx"], r["ty"], c, p[c], r[c]) for p, r in zip(prim, rtl) for c in cols if p[c] != r[c]]
    evu = sum(int(r[c]) for r in rtl for c in cols)
    tiles = sum(1 for r in rtl if any(int(r[c]) for c in cols))
    print(f"{scene.stem}: {tiles} tiles with EVU work, {evu:,} EVU clocks (rtl); frame {prim_cycles:,} cycles "
          f"(primitive) against {rtl_cycles:,} (rtl); host {prim_s:.2f} s against {rtl_s:.2f} s")
    for tx, ty, c, p, r in bad[:20]:
        print(f"  tile ({tx}, {ty}) {c}: primitive {p}, rtl {r}")
    if bad or prim_cycles != rtl_cycles or tiles == 0:
        print(f"FAILED: {len(bad)} tile columns differ" if bad else "FAILED: frame cycles differ or no EVU work")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
