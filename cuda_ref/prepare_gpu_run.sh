#!/usr/bin/env bash
# Run HERE (a Debian 12 build machine with the full TileVis build): gathers into .gpu/ (git-ignored)
# what cuda_ref/gpu_run.sh needs on a GPU machine that has CUDA, CMake and a compiler but no
# OpenEXR/Imath and none of the scene generator's dependencies:
#
#   .gpu/debs/*.deb       OpenEXR 3.1 and Imath 3.1 (runtime + dev), zlib, nlohmann-json, fmt,
#                         CLI11, GoogleTest (Ubuntu 24.04 ships none of them by default; these are
#                         unpacked, not installed, there)
#   .gpu/traces.tar.xz    every traces/scenes/*.json as a trace (`tilevis trace`), plus
#                         small/dragon_320x240.tvt for compute-sanitizer (and .gpu/tiny/dragon_128x72.tvt,
#                         .gpu/tiny/teapot_stadium_320x240.tvt and
#                         .gpu/tiny/clip_chain_64x64.tvt for k_clip_long)
#   .gpu/commit.txt       the commit the traces were made at
#   .gpu/prebuilt.tar.xz  with --prebuilt DIR: tilevis, cuda_gpu_tests, gl_raster, cuda_gpu_report
#                         built here in DIR and the shared libraries they need (gpu_run.sh build
#                         unpacks them when TILEVIS_GPU_PREBUILT=1 instead of compiling there)
#   .gpu/NAME_bin.tar.xz  with --bin NAME DIR: DIR's tilevis alone (another commit's build here, in a
#                         directory of its own or copied aside), for quick_check.sh to time beside
#                         the prebuilt one: phase base unpacks it as /tmp/NAME_bin/tilevis
#
#   bash cuda_ref/prepare_gpu_run.sh            (TILEVIS_BIN=path/to/tilevis to pick the binary)
#   bash cuda_ref/prepare_gpu_run.sh --prebuilt build-cuda        (also .gpu/prebuilt.tar.xz)
#   bash cuda_ref/prepare_gpu_run.sh --prebuilt-only build-cuda   (only .gpu/prebuilt.tar.xz)
#   bash cuda_ref/prepare_gpu_run.sh --bin base /tmp/base          (only .gpu/base_bin.tar.xz, of /tmp/base/tilevis
#                                                                   or /tmp/base/model/app/tilevis)
#
# Then, on the GPU machine, from the repository root with .gpu carried along:
#   bash cuda_ref/gpu_run.sh
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
say() { printf 'prepare_gpu_run: %s\n' "$*" >&2; }
die() { say "error: $*"; exit 1; }

PREBUILT=""
TRACES_TOO=1
BINS=()  # NAME DIR pairs
while [ $# -gt 0 ]; do
  case "$1" in
    --prebuilt) PREBUILT="${2:?--prebuilt DIR}"; shift 2 ;;
    --prebuilt-only) PREBUILT="${2:?--prebuilt-only DIR}"; TRACES_TOO=0; shift 2 ;;
    --bin) [ $# -ge 3 ] || die "--bin NAME DIR"
      [[ "$2" =~ ^[A-Za-z0-9]+$ ]] || die "--bin $2: NAME is letters and digits (it names a quick_check variant)"
      BINS+=("$2" "$3"); TRACES_TOO=0; shift 3 ;;
    *) die "unknown argument $1 (--prebuilt DIR, --prebuilt-only DIR, --bin NAME DIR)" ;;
  esac
done

BIN="${TILEVIS_BIN:-}"
if [ -z "$BIN" ]; then
  for b in build/model/app/tilevis build-cuda/model/app/tilevis; do
    if [ -x "$b" ] && "$b" trace --help 2>/dev/null | grep -q "Scene file"; then BIN="$b"; break; fi
  done
fi
[ "$TRACES_TOO" = 0 ] || { [ -n "$BIN" ] && [ -x "$BIN" ]; } ||
  die "no tilevis binary with the scene generator (build one: ./tilevis info, or set TILEVIS_BIN)"
LIMIT_MIB=52

make_traces() {
# Debian 12 packages: OpenEXR, Imath and zlib headers (OpenEXRConfig.cmake asks for ZLIB), and
# the rest of what the TILEVIS_MINIMAL build finds (TileVisDeps.cmake): nlohmann-json, fmt,
# CLI11 and GoogleTest/GMock (static libraries), so the GPU machine needs nothing installed
# beyond CUDA, CMake, Ninja and a C++ compiler.
DEBS=(libopenexr-3-1-30 libopenexr-dev libimath-3-1-29 libimath-dev zlib1g zlib1g-dev
      nlohmann-json3-dev libfmt9 libfmt-dev libcli11-dev libgtest-dev libgmock-dev)
rm -rf .gpu/debs && mkdir -p .gpu/debs
say "downloading ${DEBS[*]}"
(cd .gpu/debs && apt-get download -q "${DEBS[@]}" >/dev/null) || die "apt-get download failed (network? apt-get update?)"

rm -rf .gpu/traces && mkdir -p .gpu/traces/small
for scene in traces/scenes/*.json; do
  name="$(basename "$scene" .json)"
  say "trace $name"
  "$BIN" trace "$scene" -q -o ".gpu/traces/$name.tvt" || die "tilevis trace $scene failed"
done
# The 4K 4 spp set (gpu_run.sh baselines_4k4, cross_4k4): every scene at 3840x2160 with 4 samples
# (all built-in viewports are 16:9, so the clip-space geometry is the 1080p traces').
mkdir -p .gpu/traces/4k4
for scene in traces/scenes/*.json; do
  name="$(basename "$scene" .json)"
  say "trace $name at 3840x2160, 4 samples"
  "$BIN" trace "$scene" --viewport 3840x2160 --samples 4 -q -o ".gpu/traces/4k4/$name.tvt" ||
    die "tilevis trace $scene (4K, 4 samples) failed"
done
say "trace dragon at 320x240 (sanitizers)"
"$BIN" trace traces/scenes/dragon.json --viewport 320x240 -q -o .gpu/traces/small/dragon_320x240.tvt
# racecheck of float hybrid: a smaller one still (gpu_run.sh sanitize), outside the archive.
mkdir -p .gpu/tiny
"$BIN" trace traces/scenes/dragon.json --viewport 128x72 -q -o .gpu/tiny/dragon_128x72.tvt
# Items of 32 or more candidates at 32x32 tiles (k_clip_long), small enough for racecheck.
"$BIN" trace traces/scenes/teapot_stadium.json --viewport 320x240 -q -o .gpu/tiny/teapot_stadium_320x240.tvt
# A smaller one for racecheck of k_clip_long: one chain of clips, 4 tiles.
"$BIN" trace cuda_ref/scenes/clip_chain.json -q -o .gpu/tiny/clip_chain_64x64.tvt

# An 8-frame orbit of the bunny (the camera turning 360 degrees about y): per-frame times.
say "trace bunny orbit (8 frames)"
mkdir -p .gpu/traces/orbit
python3 - traces/scenes/bunny.json .gpu/bunny_orbit.json <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["camera"]["orbit"] = {"frames": 8, "degrees": 360, "axis": [0, 1, 0]}
s["description"] = "The bunny scene seen from 8 cameras orbiting it (a frame per 45 degrees)."
json.dump(s, open(sys.argv[2], "w"), indent=1)
PY
"$BIN" trace .gpu/bunny_orbit.json -q -o .gpu/traces/orbit/bunny_orbit.tvt || die "tilevis trace (orbit) failed"
rm -f .gpu/bunny_orbit.json

commit="$(git rev-parse HEAD 2>/dev/null || echo unknown)"
git diff --quiet HEAD -- cuda_ref model traces tests 2>/dev/null || commit="$commit+local-changes"
echo "$commit" > .gpu/commit.txt

say "compressing traces"
rm -f .gpu/traces.tar.xz
tar -C .gpu -cf - traces | xz -6 -T2 > .gpu/traces.tar.xz
rm -rf .gpu/traces
}
[ "$TRACES_TOO" = 0 ] || make_traces

# --prebuilt DIR: the binaries gpu_run.sh runs, built HERE in DIR (a Release build with nvcc, sm_90),
# with the shared libraries they need beyond the C runtime: gpu_run.sh build unpacks them instead of
# building there (TILEVIS_GPU_PREBUILT=1), so a GPU call spends no time compiling.
if [ -n "$PREBUILT" ]; then
  rm -rf .gpu/prebuilt && mkdir -p .gpu/prebuilt/bin .gpu/prebuilt/lib
  for b in model/app/tilevis tests/cuda/cuda_gpu_tests cuda_ref/gl_raster cuda_ref/cuda_gpu_report; do
    [ -x "$PREBUILT/$b" ] || die "$PREBUILT/$b missing: build it first"
    install -D -m 755 "$PREBUILT/$b" ".gpu/prebuilt/bin/$b"
  done
  for b in .gpu/prebuilt/bin/model/app/tilevis .gpu/prebuilt/bin/tests/cuda/cuda_gpu_tests .gpu/prebuilt/bin/cuda_ref/gl_raster; do
    ldd "$b" | awk '$3 ~ /^\// {print $3}'
  done | sort -u | while read -r lib; do
    case "$(basename "$lib")" in
      libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libstdc++.so* | libgcc_s.so*) ;;
      *) cp -L "$lib" .gpu/prebuilt/lib/ ;;
    esac
  done
  # The commit, marked where cuda_ref's own files differ from it; other uncommitted paths named.
  local_note=""
  git diff --quiet HEAD -- cuda_ref tests/cuda model/app/cmd_cuda.cpp 2>/dev/null || local_note="+local-changes"
  others="$(git diff --name-only HEAD -- . ':!cuda_ref' ':!tests/cuda' ':!model/app/cmd_cuda.cpp' ':!reports' ':!README.md' 2>/dev/null |
            cut -d/ -f1-2 | sort -u | paste -sd, -)"
  echo "$(git rev-parse HEAD)$local_note${others:+ (uncommitted elsewhere: $others)}" >.gpu/prebuilt/commit.txt
  rm -f .gpu/prebuilt.tar.xz
  tar -C .gpu -cf - prebuilt | xz -6 -T2 >.gpu/prebuilt.tar.xz
  rm -rf .gpu/prebuilt
  say "$(du -sh .gpu/prebuilt.tar.xz | cut -f1) of prebuilt binaries (from $PREBUILT)"
fi

# --bin NAME DIR: DIR's tilevis alone as .gpu/NAME_bin.tar.xz (its libraries are the prebuilt one's:
# build both in the same configuration).
for ((i = 0; i < ${#BINS[@]}; i += 2)); do
  name="${BINS[i]}" dir="${BINS[i + 1]}" bin=""
  for b in "$dir/tilevis" "$dir/model/app/tilevis"; do [ -x "$b" ] && { bin="$b"; break; }; done
  [ -n "$bin" ] || die "--bin $name $dir: no tilevis in $dir or $dir/model/app"
  mkdir -p .gpu
  tar -C "$(dirname "$bin")" -cf - tilevis | xz -6 -T2 >".gpu/${name}_bin.tar.xz"
  say "$(du -sh ".gpu/${name}_bin.tar.xz" | cut -f1) .gpu/${name}_bin.tar.xz (from $bin)"
done

total=$(du -sb .gpu | cut -f1)
say "$(du -sh .gpu/debs 2>/dev/null | cut -f1) of .debs, $(du -sh .gpu/traces.tar.xz 2>/dev/null | cut -f1) of traces; $((total / 1048576)) MiB in .gpu"
[ "$total" -le $((LIMIT_MIB * 1048576)) ] || die ".gpu is over ${LIMIT_MIB} MiB"
say "done: carry .gpu to the GPU machine and run bash cuda_ref/gpu_run.sh there"
