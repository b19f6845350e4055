#!/bin/sh
# Capture overhead: glmark2's frames per second per scene under Xvfb (llvmpipe), three ways:
#   plain      no interposer
#   preloaded  the interposer loaded and armed (feedback varyings linked in, every GL entry
#              point wrapped) but no frame captured
#   capturing  every frame captured (feedback replay of each draw, indices and state read
#              back, the depth buffer read at each swap), the dump written to /dev/null
# The three ways run interleaved REPEAT times (default 3); one line per scene and way gives the
# median and every run, in glmark2's own FPS.
# Usage: traces/capture/benchmark_overhead.sh [TILEVIS_CAPTURE_LIBRARY]   (SCENES, DURATION, REPEAT)
set -eu
lib=${1:-build/traces/capture/libtilevis_capture.so}
[ -r "$lib" ] || { echo "no interposer at $lib (build target tilevis_capture)" >&2; exit 1; }
lib=$(readlink -f "$lib")
scenes=${SCENES:-"build shading refract terrain jellyfish ideas"}
duration=${DURATION:-5}
repeat=${REPEAT:-3}
fps() {  # scene env...
  scene=$1; shift
  r=$(xvfb-run -a -s "-screen 0 1280x1024x24" env "$@" glmark2 -b "$scene:duration=$duration" 2>/dev/null |
      sed -n 's/.*FPS: \([0-9]*\).*/\1/p' | head -n 1)
  echo "${r:-0}"
}
median() { tr ' ' '\n' | grep . | sort -n | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
printf '%-10s %-10s %-8s %s\n' scene way median runs
for s in $scenes; do
  plain="" preloaded="" capturing=""
  i=0
  while [ "$i" -lt "$repeat" ]; do
    plain="$plain $(fps "$s" TILEVIS_BENCH=1)"
    preloaded="$preloaded $(fps "$s" LD_PRELOAD="$lib" TILEVIS_CAPTURE_OUT=/dev/null TILEVIS_CAPTURE_FRAMES=0)"
    capturing="$capturing $(fps "$s" LD_PRELOAD="$lib" TILEVIS_CAPTURE_OUT=/dev/null TILEVIS_CAPTURE_FRAMES=1000000000 TILEVIS_CAPTURE_EXIT=0)"
    i=$((i + 1))
  done
  for way in plain preloaded capturing; do
    eval "runs=\$$way"
    printf '%-10s %-10s %-8s%s\n' "$s" "$way" "$(echo "$runs" | median)" "$runs"
  done
done
