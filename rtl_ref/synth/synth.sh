#!/usr/bin/env bash
# Generic-cell synthesis of rtl_ref's units at 1, 2, 4 and 8 lanes with yosys (synth -flatten:
# internal gate library, ABC mapping), and a Markdown table of cells, flip-flops and the
# longest logic path (ltp -noff: gates between registers or ports) in OUT (default
# reports/rtl/synthesis.md). Logs go to OUT's folder/synth_logs/. Runs the points in
# parallel (JOBS, default nproc).
#   rtl_ref/synth/synth.sh [OUT] [UNIT...]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
OUT="${1:-$ROOT/reports/rtl/synthesis.md}"
shift || true
UNITS=("$@")
[ ${#UNITS[@]} -gt 0 ] || UNITS=(PairReject DepthTest Clip Occlude TileSequencer)
LANES=(${SYNTH_LANES:-1 2 4 8})
JOBS="${JOBS:-$(nproc)}"
YOSYS="${YOSYS:-yosys}"
LOGS="$(dirname "$OUT")/synth_logs"
mkdir -p "$LOGS"

unit_file() {
  case "$1" in
    PairReject) echo pair_reject.sv ;; Clip) echo clip.sv ;; Occlude) echo occlude.sv ;;
    TileSequencer) echo tile_sequencer.sv ;; DepthTest) echo depth_test.sv ;; *) echo "unknown unit $1" >&2; return 1 ;;
  esac
}
run_point() { # unit lanes
  local unit="$1" lanes="$2" ys="$LOGS/$1_x$2.ys"
  sed -e "s|@FILE@|$ROOT/rtl_ref/units/$(unit_file "$unit")|" -e "s|@UNIT@|$unit|" -e "s|@LANES@|$lanes|" \
    -e "s|@ROOT@|$ROOT|" \
    "$ROOT/rtl_ref/synth/synth_unit.ys.in" >"$ys"
  local t0=$SECONDS
  $YOSYS -q -l "$LOGS/$1_x$2.log" -s "$ys" >/dev/null 2>&1 || { echo "yosys failed: $LOGS/$1_x$2.log" >&2; return 1; }
  echo "$((SECONDS - t0))" >"$LOGS/$1_x$2.seconds"
}

if [ -z "${TABLE_ONLY:-}" ]; then  # TABLE_ONLY=1: only the table, from the logs there
pids=()
for u in "${UNITS[@]}"; do
  for l in "${LANES[@]}"; do
    while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 1; done
    run_point "$u" "$l" &
    pids+=($!)
  done
done
fail=0
for p in "${pids[@]}"; do wait "$p" || fail=1; done

fi

{
  echo "| unit | lanes | cells | flip-flops | longest path (gates) | list RAMs (black boxes) | yosys s |"
  echo "|---|---:|---:|---:|---:|---:|---:|"
  for u in "${UNITS[@]}"; do
    for l in "${LANES[@]}"; do
      log="$LOGS/${u}_x$l.log"
      if [ ! -f "$LOGS/${u}_x$l.seconds" ]; then echo "| $u | $l | not finished | | | | |"; continue; fi
      # the last statistics (synth prints its own before the script's stat)
      last="$(sed -n "$(grep -n 'Printing statistics' "$log" | tail -1 | cut -d: -f1),\$p" "$log")"
      cells=$(grep -E "^ +Number of cells:" <<<"$last" | tail -1 | awk '{print $4}')
      ffs=$( { grep -E '^\s+\$_(S?DFF|DFFE|SDFFE|SDFFCE|ALDFF|DLATCH)[A-Z0-9_]*\s+[0-9]+' <<<"$last" || true; } | { grep -v "^$" || true; } | awk '{s+=$2} END {print s+0}')
      ltp=$(grep -E "Longest topological path" "$log" | tail -1 | sed -E 's/.*length=([0-9]+).*/\1/')
      bb=$( { grep -E '^\s+\$paramod.ListRam|^\s+ListRam' <<<"$last" || true; } | { grep -v "^$" || true; } | awk '{s+=$2} END {print s+0}')
      echo "| $u | $l | $cells | $ffs | $ltp | $bb | $(cat "$LOGS/${u}_x$l.seconds") |"
    done
  done
} >"$OUT.table"
echo "wrote $OUT.table"
