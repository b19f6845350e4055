#!/usr/bin/env bash
# Generic-cell synthesis of rtl_ref's units at 1, 2, 4 and 8 lanes with yosys (internal gate
# library, ABC mapping) and a Markdown report in OUT (default reports/rtl/synthesis.md): per unit
# and lane count the cells, flip-flops, longest logic path (ltp -noff: gates between registers or
# ports), list RAMs (black boxes), yosys's wall and CPU seconds and peak memory; per unit its
# modules. The report is written by synth_report.py from the logs (SYNTH_LOGS, default build-synth/).
#   rtl_ref/synth/synth.sh [OUT] [UNIT...]
# Flows: hierarchical (default, synth_unit.ys.in): synth without -flatten, each distinct module (a
# lane, a lane's repeated arithmetic block) mapped by ABC once and counted by `stat -top` times its
# instances; the longest path on the lane's netlist flattened after mapping. SYNTH_FLAT=1: the
# earlier flow (synth_unit_flat.ys.in), synth -flatten, the whole unit in one ABC run.
# Environment: SYNTH_LANES (default "1 2 4 8"); JOBS points at a time (default 1: ABC needs up to a
# few GB per point); SYNTH_MEM_KB, the virtual-memory limit (ulimit -v) of yosys and of each ABC it
# starts (default 9437184 = 9 GiB, 0 = none); SYNTH_NICE (default 15); YOSYS (the binary);
# TABLE_ONLY=1: only the report, from the logs there.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
quote() { case "$1" in *[!A-Za-z0-9_./=:+-]*|'') printf '"%s"' "$1" ;; *) printf '%s' "$1" ;; esac; }
COMMAND=""
for v in SYNTH_FLAT SYNTH_LANES JOBS SYNTH_MEM_KB SYNTH_NICE SYNTH_LOGS YOSYS; do
  [ -z "${!v:-}" ] || COMMAND+="$v=$(quote "${!v}") "
done
COMMAND+="rtl_ref/synth/synth.sh"
for a in "$@"; do COMMAND+=" $(quote "$a")"; done
OUT="${1:-$ROOT/reports/rtl/synthesis.md}"
shift || true
UNITS=("$@")
[ ${#UNITS[@]} -gt 0 ] || UNITS=(PairReject DepthTest Clip Occlude TileSequencer)
LANES=(${SYNTH_LANES:-1 2 4 8})
JOBS="${JOBS:-1}"
YOSYS="${YOSYS:-yosys}"
MEM_KB="${SYNTH_MEM_KB:-9437184}"
NICE="${SYNTH_NICE:-15}"
LOGS="${SYNTH_LOGS:-$ROOT/build-synth}"
if [ -n "${SYNTH_FLAT:-}" ]; then FLOW=flat; YS_IN="$ROOT/rtl_ref/synth/synth_unit_flat.ys.in"
else FLOW=hierarchical; YS_IN="$ROOT/rtl_ref/synth/synth_unit.ys.in"; fi
mkdir -p "$LOGS"
command -v /usr/bin/time >/dev/null || { echo "synth.sh: needs GNU time (/usr/bin/time, Debian package time)" >&2; exit 1; }

unit_file() {
  case "$1" in
    PairReject) echo pair_reject.sv ;; Clip) echo clip.sv ;; Occlude) echo occlude.sv ;;
    TileSequencer) echo tile_sequencer.sv ;; DepthTest) echo depth_test.sv ;; *) echo "unknown unit $1" >&2; return 1 ;;
  esac
}
machine() {
  local cpu os
  cpu="$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')"
  os="$( (. /etc/os-release && echo "$PRETTY_NAME") 2>/dev/null || uname -s)"
  echo "$cpu, $(nproc) CPUs, $(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo) GiB, $os"
}
run_point() { # unit lanes
  local unit="$1" lanes="$2" base="$LOGS/$1_x$2" rc=0
  rm -f "$base".{ys,log,stat,ltp,ltp_modules,time,meta}
  sed -e "s|@FILE@|$ROOT/rtl_ref/units/$(unit_file "$unit")|" -e "s|@UNIT@|$unit|" -e "s|@LANES@|$lanes|" \
    -e "s|@ROOT@|$ROOT|" -e "s|@BASE@|$base|" "$YS_IN" >"$base.ys"
  {
    echo "flow: $FLOW"
    echo "command: $COMMAND"
    # the sources: the last commit that changed rtl_ref/units or rtl_ref/synth (HEAD moves with
    # other work in a shared checkout), and whether they differ from it
    echo "sources: $(git -C "$ROOT" log -1 --format=%h --abbrev=7 -- rtl_ref/units rtl_ref/synth)$(git -C "$ROOT" status --porcelain -- rtl_ref/units rtl_ref/synth | grep -q . && echo ' with rtl_ref/units or rtl_ref/synth modified')"
    echo "yosys: $($YOSYS -V)"
    echo "machine: $(machine)"
    echo "date: $(date -u +%F)"
  } >"$base.meta"
  # wall s, user s, system s (yosys and the ABC processes it waited for), peak resident KB of any
  # one of them, exit status
  ( [ "$MEM_KB" = 0 ] || ulimit -v "$MEM_KB"
    exec nice -n "$NICE" /usr/bin/time -f '%e %U %S %M %x' -o "$base.time" \
      $YOSYS -q -l "$base.log" -s "$base.ys" >/dev/null 2>&1 ) || rc=$?
  [ "$rc" = 0 ] || echo "yosys failed ($rc): $base.log" >&2
  return "$rc"
}

if [ -z "${TABLE_ONLY:-}" ]; then
  pids=()
  for u in "${UNITS[@]}"; do
    for l in "${LANES[@]}"; do
      while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do sleep 1; done
      run_point "$u" "$l" &
      pids+=($!)
    done
  done
  for p in "${pids[@]}"; do wait "$p" || true; done
fi

python3 "$ROOT/rtl_ref/synth/synth_report.py" --logs "$LOGS" --out "$OUT" --units "${UNITS[@]}" --lanes "${LANES[@]}"
echo "wrote $OUT"
