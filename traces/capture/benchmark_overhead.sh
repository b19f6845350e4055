#!/bin/sh
# Capture overhead: glmark2's frames per second per scene under Xvfb (llvmpipe), three ways:
#   plain      no interposer
#   preloaded  the interposer loaded and armed (feedback varyings linked in, every GL entry
#              point wrapped) but no frame captured
#   capturing  every frame captured (feedback replay of each draw, indices and state read
#              back, the depth buffer read at each swap), the dump written to /dev/null
# Prints one line per scene and way; the figures are glmark2's own FPS.
# Usage: traces/capture/benchmark_overhead.sh [TILEVIS_CAPTURE_LIBRARY]   (SCENES, DURATION)
set -eu
lib=${1:-build/traces/capture/libtilevis_capture.so}
[ -r "$lib" ] || { echo "no interposer at $lib (build target tilevis_capture)" >&2; exit 1; }
lib=$(readlink -f "$lib")
scenes=${SCENES:-"build shading refract terrain jellyfish ideas"}
duration=${DURATION:-5}
fps() {  # way scene env...
  way=$1; scene=$2; shift 2
  r=$(xvfb-run -a -s "-screen 0 1280x1024x24" env "$@" glmark2 -b "$scene:duration=$duration" 2>/dev/null |
      sed -n 's/.*FPS: \([0-9]*\).*/\1/p' | head -n 1)
  printf '%-10s %-10s %s\n' "$scene" "$way" "${r:-failed}"
}
printf '%-10s %-10s %s\n' scene way fps
for s in $scenes; do
  fps plain "$s" TILEVIS_BENCH=1
  fps preloaded "$s" LD_PRELOAD="$lib" TILEVIS_CAPTURE_OUT=/dev/null TILEVIS_CAPTURE_FRAMES=0
  fps capturing "$s" LD_PRELOAD="$lib" TILEVIS_CAPTURE_OUT=/dev/null TILEVIS_CAPTURE_FRAMES=1000000000 TILEVIS_CAPTURE_EXIT=0
done
