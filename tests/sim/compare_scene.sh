#!/usr/bin/env bash
# One CTest step of "sim == golden" on a real scene, through the CLI as a user runs it:
#   compare_scene.sh TILEVIS TRACE TILE WORKDIR [tilevis sim options...]
# golden (--mode hybrid when sim runs sim.mode=hybrid) and sim at the tile size, then `tilevis compare`: every covered sample the same
# id, every per-tile functional counter and every visible area equal, or the step fails.
set -euo pipefail
bin=$1 trace=$2 tile=$3 work=$4
shift 4
name="$(basename "$trace" .tvt)_t${tile}${1:+_$(echo "$*" | tr -c 'A-Za-z0-9_.=' '_')}"
rm -rf "${work:?}/$name"
mkdir -p "$work/$name"
golden_mode=analytic
case " $* " in *sim.mode=hybrid*) golden_mode=hybrid ;; esac
"$bin" golden "$trace" --tile "$tile" --mode "$golden_mode" -o "$work/$name/golden" >/dev/null
"$bin" sim "$trace" --tile "$tile" "$@" -o "$work/$name/sim"
"$bin" compare "$work/$name/sim" "$work/$name/golden"
for f in tile_cycles.exr tile_cycles.png config.json; do
  [ -s "$work/$name/sim/$f" ] || { echo "compare_scene: sim wrote no $f" >&2; exit 1; }
done
python3 - "$work/$name/sim/compare.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
bad = []
if c["mismatched_samples"] != 0 or c["sample_agreement"] != 1.0: bad.append("ids differ")
if c["tile_counter_mismatches"] != 0: bad.append(f'{c["tile_counter_mismatches"]} tile counter cells differ')
if c.get("area_mismatches", 0) != 0: bad.append("visible areas differ")
if len(c["compared_tile_columns"]) < 10: bad.append("golden's tile columns not all compared")
if bad: sys.exit("compare_scene: " + "; ".join(bad))
PY
