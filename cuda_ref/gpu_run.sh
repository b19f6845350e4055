#!/usr/bin/env bash
# The cuda_ref cross-check on a GPU machine (Ubuntu 24.04, CUDA 13, CMake, Ninja, g++; no OpenEXR,
# SystemC, GLM, assimp, CGAL, Boost, no network). Run from the repository root with .gpu/ carried
# along (made here-and-now by cuda_ref/prepare_gpu_run.sh on a full build machine):
#
#   bash cuda_ref/gpu_run.sh [all | build | test | baselines | cross | baselines_4k4 | cross_4k4 | orbit
#                             | sanitize | profile | report]...
#
#   build     unpack .gpu/debs into /tmp/sysroot (dpkg -x), configure a TILEVIS_MINIMAL Release
#             build with Ninja in build-gpu pointed at it, build, unpack .gpu/traces.tar.xz; with
#             TILEVIS_GPU_PREBUILT=1, unpack .gpu/prebuilt.tar.xz (binaries built on the preparing
#             machine: prepare_gpu_run.sh --prebuilt) into build-gpu instead of compiling
#   test      ctest: cuda_ref's GPU tests (label gpu; they must run, not skip) and its host tests
#   baselines every scene's z-buffers: the exact truth (CPU), OpenGL through EGL (gl_raster; .gl
#             carried: the loader .debs, unpacked into / as the device README says), the CUDA
#             z-buffers tiled (exact) and naive, each compared with the truth
#   baselines_4k4, cross_4k4   the same on the 4K 4 spp traces (.gpu traces/4k4) into
#             build-gpu/work/4k4: GL with 4x multisample targets, tiles 32 only, no golden
#             (TILEVIS_GPU_RUNS_4K4 runs, default 5)
#   profile   Nsight Compute's time per kernel (ncu --clock-control none) of tilevis cuda on the
#             scenes of TILEVIS_NCU (default "slivers:float million:float million:zb_tiled"):
#             $OUT/ncu_<scene>_<what>.txt
#   cross     every scene at tiles 16, 32, 64: golden on the CPU (in parallel, first), then
#             tilevis cuda exact and float on the GPU one at a time (--runs 20 after warm-up),
#             tilevis compare of each against golden and of float against exact
#   orbit     the 8-frame bunny orbit: GL, z-buffers and analytic (32x32, both precisions) per frame,
#             and the orbit as one sequence through one pipeline (tilevis cuda --laps: first sight,
#             new frame right after another frame, the known frame's graph)
#   sanitize  compute-sanitizer memcheck and racecheck on a small trace, both precisions
#   report    $OUT/<device>.json and .md (reports/cuda/ without $OUT), the table printed last
#
# $OUT receives <device>.json, <device>.md, work_json.tar.xz (every run's stats.json and
# compare.json) and logs.tar.xz. Phases resume: results already in build-gpu/work are kept, so a run cut short by a time limit
# continues where it stopped. Environment: OUT, TILEVIS_GPU_SCENES (names, default: all),
# TILEVIS_GPU_TILES (default "16 32 64"), TILEVIS_GPU_RUNS (default 20), JOBS (default nproc),
# TILEVIS_GPU_PAIR_BUDGET (default 60: the hybrid runs' and golden hybrid's --pair-budget, so that
# a tile of more triangles x edges goes per pixel; 0: none; reports/cuda/hybrid_budget_h200.md),
# TILEVIS_GPU_DEVICE=cpu (the host emulation: tries the script on a machine without a GPU),
# TILEVIS_TEST_LABEL (ctest labels, default "gpu|cuda"; "gpu" leaves the host emulation to CI).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BUILD="$ROOT/build-gpu"
WORK="$BUILD/work"
TRACES="$BUILD/gpu_traces"
SYSROOT=/tmp/sysroot
REPORT_DIR="${OUT:-$ROOT/reports/cuda}"
LOGS="$BUILD/logs"
TILES="${TILEVIS_GPU_TILES:-16 32 64}"
RUNS="${TILEVIS_GPU_RUNS:-20}"
JOBS="${JOBS:-$(nproc)}"
PAIR_BUDGET="${TILEVIS_GPU_PAIR_BUDGET:-60}"
[[ "$PAIR_BUDGET" =~ ^[0-9]+$ ]] || { echo "gpu_run: TILEVIS_GPU_PAIR_BUDGET=$PAIR_BUDGET: a whole number" >&2; exit 2; }
DEVICE="${TILEVIS_GPU_DEVICE:-gpu}"  # cpu: the host emulation, to try this script without a GPU
BIN="$BUILD/model/app/tilevis"
# The trace set the baselines and cross phases work on: 1080p (the traces as made, into $WORK) or
# 4k4 (3840x2160, 4 samples, into $WORK/4k4).
SET=1080p
SET_TRACES="$TRACES"
SET_WORK="$WORK"
use_set() {
  SET="$1"
  case "$1" in
    1080p) SET_TRACES="$TRACES"; SET_WORK="$WORK" ;;
    4k4) SET_TRACES="$TRACES/4k4"; SET_WORK="$WORK/4k4" ;;
  esac
  mkdir -p "$SET_WORK"
}
PREBUILT="${TILEVIS_GPU_PREBUILT:-0}"
[ -d "$BUILD/prebuilt_lib" ] && export LD_LIBRARY_PATH="$BUILD/prebuilt_lib:${LD_LIBRARY_PATH:-}"
export PATH="/usr/local/cuda/bin:/usr/local/cuda/compute-sanitizer:$PATH"
export LD_LIBRARY_PATH="$SYSROOT/usr/lib/x86_64-linux-gnu:$SYSROOT/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
mkdir -p "$LOGS" "$WORK/meta" "$REPORT_DIR"
# What comes back is few files: the report, the per-run JSON and the logs, each one archive.
pack_logs() { tar -C "$LOGS" -cf - . 2>/dev/null | xz -6 >"$REPORT_DIR/logs.tar.xz" || true; }
trap pack_logs EXIT

say() { printf '\033[1mgpu_run:\033[0m %s\n' "$*" >&2; }
die() { say "error: $*"; exit 1; }
t_start=$SECONDS
elapsed() { echo "$((SECONDS - t_start)) s"; }

unpack_traces() {
  if [ ! -f "$TRACES/bunny.tvt" ]; then
    say "unpack traces"
    mkdir -p "$TRACES" && tar -C "$TRACES" --strip-components=1 -xJf .gpu/traces.tar.xz
  fi
}

phase_build() {
  [ -d .gpu/debs ] && [ -f .gpu/traces.tar.xz ] || die ".gpu/ missing: run cuda_ref/prepare_gpu_run.sh on a build machine and carry .gpu"
  if [ "$PREBUILT" = 1 ]; then
    [ -f .gpu/prebuilt.tar.xz ] || die "TILEVIS_GPU_PREBUILT=1 but no .gpu/prebuilt.tar.xz (prepare_gpu_run.sh --prebuilt DIR)"
    say "unpack prebuilt binaries ($(cat .gpu/commit.txt 2>/dev/null))"
    mkdir -p "$BUILD"
    tar -C "$BUILD" -xJf .gpu/prebuilt.tar.xz
    cp -a "$BUILD/prebuilt/bin/." "$BUILD/"
    rm -rf "$BUILD/prebuilt_lib" && mv "$BUILD/prebuilt/lib" "$BUILD/prebuilt_lib"
    cp "$BUILD/prebuilt/commit.txt" "$WORK/meta/prebuilt_commit.txt"
    export LD_LIBRARY_PATH="$BUILD/prebuilt_lib:${LD_LIBRARY_PATH:-}"
    "$BIN" cuda --help | grep -q precision || die "the prebuilt tilevis does not run here"
    unpack_traces
    say "build done: prebuilt ($(elapsed))"
    return
  fi
  mkdir -p "$SYSROOT"
  for d in .gpu/debs/*.deb; do dpkg -x "$d" "$SYSROOT"; done
  # Debian's libz.so is an absolute link into /lib: name the library and headers explicitly.
  local zinc=/usr/include zlib=""
  [ -f /usr/include/zlib.h ] || zinc="$SYSROOT/usr/include"
  for z in /usr/lib/x86_64-linux-gnu/libz.so /usr/lib/x86_64-linux-gnu/libz.so.1 /lib/x86_64-linux-gnu/libz.so.1 \
           "$SYSROOT"/lib/x86_64-linux-gnu/libz.so.1; do
    if [ -e "$z" ]; then zlib="$z"; break; fi
  done
  [ -n "$zlib" ] || die "no libz.so.1 found"
  say "configure (TILEVIS_MINIMAL; OpenEXR, nlohmann-json, fmt, CLI11, GoogleTest from $SYSROOT; zlib $zlib)"
  # The carried packages only: no system-wide package registry, and $SYSROOT first.
  cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTILEVIS_MINIMAL=ON \
        -DCMAKE_PREFIX_PATH="$SYSROOT/usr" -DZLIB_INCLUDE_DIR="$zinc" -DZLIB_LIBRARY="$zlib" \
        -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF \
        -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc >"$LOGS/configure.log" 2>&1 ||
    { tail -n 30 "$LOGS/configure.log" >&2; die "configure failed"; }
  # Where each dependency came from (the report shows it: carried, or the machine's own).
  grep -E '^(nlohmann_json|fmt|CLI11|GTest|OpenEXR|Imath)_DIR:' "$BUILD/CMakeCache.txt" >"$WORK/meta/deps.txt" || true
  say "dependencies: $(tr '\n' ' ' <"$WORK/meta/deps.txt")"
  say "build ($JOBS jobs)"
  # Only what the phases run: the tool, cuda_ref's tests (labels gpu, cuda) and tools.
  cmake --build "$BUILD" -j "$JOBS" --target tilevis cuda_gpu_tests cuda_emulation_tests cuda_predicate_tests \
        gl_raster cuda_gpu_report >"$LOGS/build.log" 2>&1 || { grep -E "error|FAILED" "$LOGS/build.log" | head -n 30 >&2; die "build failed"; }
  [ -x "$BIN" ] || die "no $BIN after the build"
  # cuda_ref on its own (its CMakeLists.txt as a project): CUDA, CMake and the trace reader only.
  cmake -S "$ROOT/cuda_ref" -B "$BUILD-standalone" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_CUDA_COMPILER=/usr/local/cuda/bin/nvcc >"$LOGS/standalone.log" 2>&1 &&
    cmake --build "$BUILD-standalone" -j "$JOBS" >>"$LOGS/standalone.log" 2>&1 &&
    echo "standalone cuda_ref build: ok" >"$WORK/meta/standalone.txt" ||
    echo "standalone cuda_ref build: FAILED (see logs/standalone.log)" >"$WORK/meta/standalone.txt"
  say "$(cat "$WORK/meta/standalone.txt")"
  "$BIN" cuda --help | grep -q precision || die "tilevis has no cuda command"
  unpack_traces
  say "build done ($(elapsed))"
}

phase_test() {
  say "ctest: cuda_ref GPU and host tests"
  local log="$LOGS/ctest.log" rc=0
  # The built-in scenes' traces (GpuBuiltInScenes: exact hybrid = golden hybrid, float signs).
  export TILEVIS_GPU_TRACES="$TRACES"
  if [ "$PREBUILT" = 1 ]; then
    # No CTest files with prebuilt binaries: the GPU tests' binary itself (the host emulation
    # tests ran where the binaries were built).
    "$BUILD/tests/cuda/cuda_gpu_tests" ${TILEVIS_GTEST_FILTER:+--gtest_filter="$TILEVIS_GTEST_FILTER"} >"$log" 2>&1 || rc=$?
    local passed failed
    passed="$(grep -oE '\[  PASSED  \] [0-9]+' "$log" | grep -oE '[0-9]+$' || echo 0)"
    failed="$(grep -cE '^\[  FAILED  \] [A-Za-z]' "$log" || true)"
    echo "cuda_gpu_tests (prebuilt): $passed passed, $failed failed; $(grep -c '\[  SKIPPED \]' "$log" || true) skipped (exit $rc)" \
      >"$WORK/meta/gpu_tests.txt"
    say "$(cat "$WORK/meta/gpu_tests.txt")"
    [ "$rc" -eq 0 ] || { grep -E "FAILED|Failure" "$log" | head -n 20 >&2; say "tests FAILED (continuing: see $log)"; }
    return
  fi
  ctest --test-dir "$BUILD" -L "${TILEVIS_TEST_LABEL:-gpu|cuda}" -j 4 --output-on-failure >"$log" 2>&1 || rc=$?
  local summary skipped
  summary="$(grep -E "tests passed|tests failed" "$log" | tail -n 1 || true)"
  skipped="$(grep -c "Skipped" "$log" || true)"
  echo "$summary; $skipped skipped (exit $rc)" >"$WORK/meta/gpu_tests.txt"
  say "ctest: $summary; $skipped skipped"
  [ "$rc" -eq 0 ] || { grep -E "Failed|\*\*\*" "$log" | head -n 20 >&2; say "tests FAILED (continuing: see $log)"; }
  [ "$skipped" -eq 0 ] || say "warning: GPU tests skipped: is the GPU visible? (nvidia-smi)"
}

scenes() {
  if [ -n "${TILEVIS_GPU_SCENES:-}" ]; then echo "$TILEVIS_GPU_SCENES"; return; fi
  for t in "$SET_TRACES"/*.tvt; do basename "$t" .tvt; done
}

phase_cross() {
  [ -x "$BIN" ] || die "not built: run the build phase first"
  local s t jobs=() tiles="$TILES" runs="$RUNS" tag="" base=on
  # At 4K 4 spp the analytic runs time the tiled z-buffer only (the naive one's big triangles take
  # seconds a run there; its time is the baselines phase's).
  [ "$SET" = 1080p ] || { tiles=32; runs="${TILEVIS_GPU_RUNS_4K4:-5}"; tag="${SET}_"; base=tiled; }
  # Golden (CPU) first and all at once, so that no CPU load overlaps the timed GPU runs.
  for s in $(scenes); do
    for t in $tiles; do
      [ "$SET" = 1080p ] || continue  # no golden at 4K 4 spp (its CPU time): timings and ratios only
      [ -f "$SET_WORK/$s/t$t/golden/stats.json" ] || jobs+=("$s $t analytic golden 0")
      [ -f "$SET_WORK/$s/t$t/golden_hybrid/stats.json" ] || jobs+=("$s $t hybrid golden_hybrid $PAIR_BUDGET")
    done
  done
  if [ ${#jobs[@]} -gt 0 ]; then
    say "golden: ${#jobs[@]} runs on $JOBS cores"
    printf '%s\n' "${jobs[@]}" | xargs -P "$JOBS" -L 1 bash -c \
      '"$0" golden "$1/$4.tvt" --tile "$5" --mode "$6" --pair-budget "$8" -o "$2/$4/t$5/$7" >"$3/$7_$4_$5.log" 2>&1 || echo "golden $4 $5 $6 failed" >&2' \
      "$BIN" "$SET_TRACES" "$SET_WORK" "$LOGS" 2>&1 | tee -a "$LOGS/errors.log" >&2 || true
  fi
  say "golden done ($(elapsed))"
  for s in $(scenes); do
    for t in $tiles; do
      local d="$SET_WORK/$s/t$t"
      for p in exact float hybrid_exact hybrid_float; do
        local mode=analytic prec="$p" ref=golden budget=()
        case "$p" in hybrid_*) mode=hybrid prec="${p#hybrid_}" ref=golden_hybrid budget=(--pair-budget "$PAIR_BUDGET") ;; esac
        if [ ! -f "$d/$p/stats.json" ]; then
          local hw; hw="$(hw_ms "$s")"
          "$BIN" cuda "$SET_TRACES/$s.tvt" --tile "$t" --mode "$mode" --precision "$prec" "${budget[@]}" --runs "$runs" --device "$DEVICE" \
            -o "$d/$p" ${hw:+--hw-raster-ms "$hw"} --baselines "$base" \
            >"$LOGS/cuda_${tag}${s}_${t}_$p.log" 2>&1 || { say "cuda $s $t $p failed: $(tail -n 1 "$LOGS/cuda_${tag}${s}_${t}_$p.log")"; continue; }
        fi
        if [ -f "$d/$ref/stats.json" ] && [ ! -f "$d/cmp_$p/compare.json" ]; then
          "$BIN" compare "$d/$ref" "$d/$p" -o "$d/cmp_$p" >"$LOGS/compare_${tag}${s}_${t}_$p.log" 2>&1 || say "compare $s $t $p failed"
        fi
        # Hybrid against the exact truth (ids): float hybrid's disagreement measured too.
        if [ "$mode" = hybrid ] && [ -f "$SET_WORK/$s/truth/stats.json" ] && [ ! -f "$d/cmp_truth_$p/compare.json" ]; then
          "$BIN" compare "$SET_WORK/$s/truth" "$d/$p" -o "$d/cmp_truth_$p" >/dev/null 2>&1 || say "compare truth $s $t $p failed"
        fi
      done
      if [ -f "$d/exact/stats.json" ] && [ -f "$d/float/stats.json" ] && [ ! -f "$d/cmp_float_exact/compare.json" ]; then
        "$BIN" compare "$d/exact" "$d/float" -o "$d/cmp_float_exact" >/dev/null 2>&1 || say "compare $s $t float/exact failed"
      fi
      # An exact mismatch is a bug: say where, with the cause of every mismatched sample.
      if grep -qE '"(mismatched_samples|tile_counter_mismatches)": [1-9]' "$d/cmp_hybrid_exact/compare.json" 2>/dev/null; then
        say "MISMATCH: $s at $t (exact hybrid vs golden hybrid)"
      fi
      if grep -qE '"(mismatched_samples|tile_counter_mismatches)": [1-9]' "$d/cmp_exact/compare.json" 2>/dev/null; then
        say "MISMATCH: $s at $t (exact vs golden): explaining"
        "$BIN" compare "$d/golden" "$d/exact" --explain "$SET_TRACES/$s.tvt" -o "$d/cmp_exact_explain" \
          >"$LOGS/explain_${tag}${s}_$t.txt" 2>&1 || true
      fi
      say "$SET $s at $t done ($(elapsed))"
    done
  done
}

# The z-buffer baselines of every scene (1 sample, as traced): the exact truth (CPU, all at
# once, before any timing), the GPU's own rasteriser through OpenGL/EGL (gl_raster, its ids
# classified against the truth) when a GL driver loads, and the CUDA z-buffers (tiled exact,
# naive) compared with the truth. The cross phase passes the GL time on (hw_raster_ratio).
phase_baselines() {
  [ -x "$BIN" ] || die "not built: run the build phase first"
  local s jobs=() runs="$RUNS" tag=""
  [ "$SET" = 1080p ] || { runs="${TILEVIS_GPU_RUNS_4K4:-5}"; tag="${SET}_"; }
  if [ -d .gl ] && ! ldconfig -p | grep -q libEGL.so.1; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
  fi
  local vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  [ -f "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"
  # TILEVIS_GPU_TRUTH_4K4=0: no truth at 4K 4 spp, so no comparison there either; the scenes of
  # TILEVIS_GPU_TRUTH_SKIP_4K4 (default stack: its CPU truth alone takes 194 s on 16 cores) get none.
  for s in $(scenes); do
    [ "$SET" = 1080p ] || [ "${TILEVIS_GPU_TRUTH_4K4:-1}" = 1 ] || break
    [ "$SET" = 1080p ] || ! [[ " ${TILEVIS_GPU_TRUTH_SKIP_4K4-stack} " == *" $s "* ]] || continue
    [ -f "$SET_WORK/$s/truth/stats.json" ] || jobs+=("$s")
  done
  if [ ${#jobs[@]} -gt 0 ]; then
    say "truth: ${#jobs[@]} runs on $JOBS cores"
    printf '%s\n' "${jobs[@]}" | TAG="$tag" xargs -P "$JOBS" -L 1 bash -c \
      '"$0" golden "$1/$4.tvt" --truth -o "$2/$4/truth" >"$3/truth_$TAG$4.log" 2>&1 || echo "truth $4 failed" >&2' \
      "$BIN" "$SET_TRACES" "$SET_WORK" "$LOGS" 2>&1 | tee -a "$LOGS/errors.log" >&2 || true
  fi
  for s in $(scenes); do
    local d="$SET_WORK/$s" truth_arg=(--truth "$SET_WORK/$s/truth")
    [ "$SET" = 1080p ] || truth_arg=()  # multisample: the GL's ids are not read back
    if [ ! -f "$d/gl/stats.json" ]; then
      "$BUILD/cuda_ref/gl_raster" "$SET_TRACES/$s.tvt" --runs "$runs" "${truth_arg[@]}" -o "$d/gl" >"$LOGS/gl_$tag$s.log" 2>&1 ||
        say "gl_raster $SET $s: $(tail -n 1 "$LOGS/gl_$tag$s.log")"
    fi
    for z in tiled naive; do
      if [ ! -f "$d/zb_$z/stats.json" ]; then
        "$BIN" cuda "$SET_TRACES/$s.tvt" --zbuffer "$z" --runs "$runs" --device "$DEVICE" -o "$d/zb_$z" \
          >"$LOGS/zb_$tag${s}_$z.log" 2>&1 || say "zbuffer $z $SET $s failed: $(tail -n 1 "$LOGS/zb_$tag${s}_$z.log")"
      fi
      if [ -f "$d/zb_$z/stats.json" ] && [ -f "$d/truth/stats.json" ] && [ ! -f "$d/cmp_zb_$z/compare.json" ]; then
        "$BIN" compare "$d/truth" "$d/zb_$z" -o "$d/cmp_zb_$z" >/dev/null 2>&1 || say "compare zbuffer $z $s failed"
      fi
    done
    say "$SET $s baselines: $(grep -ho '"hw_raster_ms": [0-9.e-]*' "$d/gl/stats.json" 2>/dev/null || echo 'no GL'); $(grep -ho '"mismatched_samples": [0-9]*' "$d/cmp_zb_tiled/compare.json" 2>/dev/null || echo 'no tiled compare') ($(elapsed))"
  done
}

# The 8-frame orbit (orbit/bunny_orbit.tvt): every frame through GL, the CUDA z-buffers and the
# analytic pipeline at 32x32 in both precisions. Per frame, the graph replay of the known frame
# and the stream run (a frame the pipeline sizes anew on the host) are both reported.
phase_orbit() {
  [ -x "$BIN" ] || die "not built: run the build phase first"
  local t="$TRACES/orbit/bunny_orbit.tvt" k p
  [ -f "$t" ] || { say "no orbit trace (prepare_gpu_run.sh makes it)"; return; }
  local vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  [ -f "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"
  for k in 0 1 2 3 4 5 6 7; do
    local d="$WORK/orbit/bunny/f$k"
    mkdir -p "$d"
    [ -f "$d/gl/stats.json" ] || "$BUILD/cuda_ref/gl_raster" "$t" --frame "$k" --runs "$RUNS" -o "$d/gl" >"$LOGS/orbit_gl_$k.log" 2>&1 || true
    local hw; hw="$({ grep -ho '"hw_raster_ms": [0-9.e+-]*' "$d/gl/stats.json" 2>/dev/null || true; } | sed 's/.*: //')"
    for p in exact float; do
      [ -f "$d/$p/stats.json" ] || "$BIN" cuda "$t" --frame "$k" --tile 32 --precision "$p" --runs "$RUNS" \
        ${hw:+--hw-raster-ms "$hw"} -o "$d/$p" >"$LOGS/orbit_${p}_$k.log" 2>&1 || say "orbit frame $k $p failed"
    done
  done
  for p in exact float; do
    local q="$WORK/orbit/bunny/seq_$p"
    [ -f "$q/sequence.json" ] || "$BIN" cuda "$t" --laps "${TILEVIS_GPU_LAPS:-5}" --tile 32 --precision "$p" \
      --runs "$RUNS" -o "$q" >"$LOGS/orbit_seq_$p.log" 2>&1 || say "orbit sequence $p failed: $(tail -n 1 "$LOGS/orbit_seq_$p.log")"
    [ -f "$q/sequence.json" ] && cat "$LOGS/orbit_seq_$p.log" >&2
  done
  say "orbit done ($(elapsed))"
}

hw_ms() {  # the GL time of a scene in the current set, or nothing
  { grep -ho '"hw_raster_ms": [0-9.e+-]*' "$SET_WORK/$1/gl/stats.json" 2>/dev/null || true; } | head -n 1 | sed 's/.*: //'
}

# One compute-sanitizer run, its summary line into meta/sanitizer.txt (and said):
#   sanitize_one TOOL LABEL LOG [the tool's own options] -- COMMAND...
sanitize_one() {
  local tool="$1" label="$2" log="$3" rc=0 line opts=()
  shift 3
  while [ "$1" != "--" ]; do opts+=("$1"); shift; done
  shift
  # Phases resume: a check filed by an earlier call (one its time limit cut short) is not run again.
  if grep -qF "$tool $label: " "$WORK/meta/sanitizer.txt.tmp" 2>/dev/null; then
    say "$tool $label: filed earlier"
    return
  fi
  timeout "${TILEVIS_SANITIZE_TIMEOUT:-300}" compute-sanitizer --tool "$tool" "${opts[@]}" --error-exitcode 3 "$@" \
    >"$log" 2>&1 || rc=$?
  line="$(grep -E "ERROR SUMMARY|RACECHECK SUMMARY" "$log" | tail -n 1 || true)"
  [ "$rc" = 124 ] && line="did not finish in ${TILEVIS_SANITIZE_TIMEOUT:-300} s"
  echo "$tool $label: ${line:-no summary} (exit $rc)" >>"$WORK/meta/sanitizer.txt.tmp"
  # Filed as it goes, so that a call's time limit loses no finished check (the report reads this).
  paste -sd ';' "$WORK/meta/sanitizer.txt.tmp" >"$WORK/meta/sanitizer.txt"
  say "$tool $label: ${line:-no summary} (exit $rc)"
}

phase_sanitize() {
  [ -x "$BIN" ] || die "not built: run the build phase first"
  # TILEVIS_SANITIZE_TRACE: another trace in place of dragon 320x240 (say one whose items reach
  # k_clip_long: .gpu/tiny/teapot_stadium_320x240.tvt).
  local small="${TILEVIS_SANITIZE_TRACE:-$TRACES/small/dragon_320x240.tvt}" tool p
  command -v compute-sanitizer >/dev/null || { echo "compute-sanitizer not found" >"$WORK/meta/sanitizer.txt"; return; }
  touch "$WORK/meta/sanitizer.txt.tmp"  # kept: the checks it lists are not run again
  export TILEVIS_CUDA_NO_LAUNCH_PROBE=1  # no launch-cost probe (2,300 empty launches) under the tools
  # TILEVIS_SANITIZE_ONLY: "tool:what ..." (what: a precision below, clip_long_exact,
  # clip_long_float or dev_overflow) narrows the runs.
  wanted() { [ -z "${TILEVIS_SANITIZE_ONLY:-}" ] || [[ " $TILEVIS_SANITIZE_ONLY " == *" $1:$2 "* ]]; }
  for tool in memcheck racecheck; do
    for p in exact float zb_tiled zb_naive hybrid_exact hybrid_float; do
      wanted "$tool" "$p" || continue
      local args=(--tile 32 --precision "$p" --baselines off)
      # Hybrid with small lists, so that tiles go per pixel (budget) and its kernels run.
      case "$p" in
        zb_*) args=(--zbuffer "${p#zb_}") ;;
        hybrid_*) args=(--tile 32 --mode hybrid --list-capacity 24,8 --precision "${p#hybrid_}" --baselines off) ;;
      esac
      # racecheck of float hybrid did not finish on the 320x240 trace inside a lease: the 128x72
      # one (.gpu/tiny, prepare_gpu_run.sh) when carried.
      local trace="$small"
      if [ "$tool $p" = "racecheck hybrid_float" ] && [ -f .gpu/tiny/dragon_128x72.tvt ]; then
        trace=.gpu/tiny/dragon_128x72.tvt
      fi
      sanitize_one "$tool" "$p ($(basename "$trace" .tvt))" "$LOGS/sanitizer_${tool}_$p.log" -- \
        "$BIN" cuda "$trace" "${args[@]}" --runs 1 -o "$WORK/sanitize/${tool}_$p"
    done
    # The clip stage's long chains (k_clip_long: the tree of walks, the per-warp stage, the list
    # of long items), the tool on that kernel only (the rest runs uninstrumented), one warm-up,
    # on .gpu/tiny/teapot_stadium_320x240.tvt and .gpu/tiny/clip_chain_64x64.tvt
    # (cuda_ref/scenes/clip_chain.json: 48 stacked quads in 4 tiles, back triangles of up to 94
    # candidates, 1,205 pieces in one tile). Under racecheck the tree's waiting warps sleep
    # 20 us between looks (TILEVIS_CLIP_SPIN_NS; 32 ns natively): with float's 16 warps a block
    # and 32 ns or 1 us the run made no progress in 120-400 s (the waiters' instrumented looks
    # crowd out the warp that makes the piece), with 20 us the chain takes 42 s (H200).
    local long p name label
    for long in .gpu/tiny/teapot_stadium_320x240.tvt .gpu/tiny/clip_chain_64x64.tvt; do
      [ -f "$long" ] || continue
      for p in exact float; do
        wanted "$tool" "clip_long_$p" || continue
        name="clip_long_${p}_$(basename "$long" .tvt)"
        label="k_clip_long $p ($(basename "$long" .tvt))"
        unset TILEVIS_CLIP_SPIN_NS
        if [ "$tool" = racecheck ]; then
          export TILEVIS_CLIP_SPIN_NS=20000
          label="k_clip_long $p ($(basename "$long" .tvt), waiting warps sleep 20 us)"
        fi
        sanitize_one "$tool" "$label" "$LOGS/sanitizer_${tool}_$name.log" --kernel-name kns=k_clip_long -- \
          "$BIN" cuda "$long" --tile 32 --precision "$p" --baselines off --warmup 1 --runs 1 -o "$WORK/sanitize/${tool}_$name"
      done
    done
    unset TILEVIS_CLIP_SPIN_NS
    # The device-sized graph past its bounds (a launch that overflows: every later count 0, the
    # frame run again with host reads): the GPU test that makes it happen, under the tool.
    local gt="$BUILD/tests/cuda/cuda_gpu_tests"
    if [ -x "$gt" ] && wanted "$tool" dev_overflow; then
      sanitize_one "$tool" "device-sized overflow (cuda_gpu_tests DeviceSizedGraphPastItsBoundsRunsAgain, cubes 320x240)" \
        "$LOGS/sanitizer_${tool}_dev_overflow.log" -- "$gt" --gtest_filter=Gpu.DeviceSizedGraphPastItsBoundsRunsAgain
    fi
  done
  paste -sd ';' "$WORK/meta/sanitizer.txt.tmp" >"$WORK/meta/sanitizer.txt"
  rm -f "$WORK/meta/sanitizer.txt.tmp"
}

# Nsight Compute (ncu in CUDA 13; --clock-control none: the clocks as found) per kernel of tilevis cuda:
# TILEVIS_NCU names scene:what items (what: exact, float, hybrid_exact, hybrid_float, zb_tiled,
# zb_naive; a scene 4k4/NAME takes the 4K 4 spp trace): the time per kernel over every launch of
# one run (synchronous runs, graph replays); TILEVIS_NCU_DETAIL names scene:what:kernel items: that
# kernel's first launch after a warm-up run with the speed-of-light, occupancy, launch, warp-state
# and memory sections. Outputs in $OUT/ncu.tar.xz.
phase_profile() {
  [ -x "$BIN" ] || die "not built: run the build phase first"
  local ncu_bin=ncu item
  command -v ncu >/dev/null || ncu_bin=/usr/local/cuda/bin/ncu
  [ -x "$(command -v "$ncu_bin")" ] || { say "no ncu"; echo "ncu not found" >"$WORK/meta/ncu.txt"; return; }
  mkdir -p "$LOGS/ncu"
  "$ncu_bin" --version | tail -n 1 >"$WORK/meta/ncu.txt"
  args_of() {  # what -> tilevis cuda arguments
    case "$1" in
      zb_*) echo "--zbuffer ${1#zb_} --runs 1 --warmup 1" ;;
      hybrid_*) echo "--tile 32 --mode hybrid --pair-budget $PAIR_BUDGET --precision ${1#hybrid_} --runs 1 --warmup 1 --baselines off" ;;
      *) echo "--tile 32 --precision $1 --runs 1 --warmup 1 --baselines off" ;;
    esac
  }
  for item in ${TILEVIS_NCU-slivers:float million:float million:zb_tiled}; do
    local scene="${item%%:*}" what="${item#*:}" trace="$TRACES/${item%%:*}.tvt"
    local name="${scene//\//_}_$what"
    # shellcheck disable=SC2046
    timeout 240 "$ncu_bin" --clock-control none --metrics gpu__time_duration.sum --print-summary per-kernel \
      "$BIN" cuda "$trace" $(args_of "$what") -o "$WORK/ncu/$name" >"$LOGS/ncu/summary_$name.txt" 2>&1 ||
      say "ncu $item failed: $(tail -n 2 "$LOGS/ncu/summary_$name.txt")"
    say "ncu $item ($(elapsed))"
  done
  for item in ${TILEVIS_NCU_DETAIL-}; do
    local scene="${item%%:*}" rest="${item#*:}"
    local what="${rest%%:*}" kernel="${rest#*:}" trace="$TRACES/${item%%:*}.tvt"
    local name="${scene//\//_}_${what}_$kernel"
    # shellcheck disable=SC2046
    timeout 240 "$ncu_bin" --clock-control none -k "regex:$kernel" --launch-skip 1 --launch-count 1 \
      --section SpeedOfLight --section Occupancy --section LaunchStats --section WarpStateStats \
      --section MemoryWorkloadAnalysis --section ComputeWorkloadAnalysis --section SchedulerStats \
      "$BIN" cuda "$trace" $(args_of "$what") -o "$WORK/ncu/$name" >"$LOGS/ncu/detail_$name.txt" 2>&1 ||
      say "ncu detail $item failed: $(tail -n 2 "$LOGS/ncu/detail_$name.txt")"
    say "ncu detail $item ($(elapsed))"
  done
  tar -C "$LOGS" -cf - ncu | xz -6 >"$REPORT_DIR/ncu.tar.xz" || true
}

phase_report() {
  local device commit
  device="$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -n 1 || true)"
  [ -n "$device" ] || device="$(grep -h '^  "device":' "$WORK"/*/t*/exact/stats.json 2>/dev/null | head -n 1 | sed 's/.*"device": "\(.*\)".*/\1/')"
  [ -n "$device" ] || device=unknown-gpu
  # The source's commit: .gpu/commit_src.txt, which the sender writes for the tree it sends (a
  # copied tree's own .git, if any, may be older); else .gpu/commit.txt, the checkout that
  # prepare_gpu_run.sh made the traces from. The traces' commit is named beside it.
  commit="$(cat .gpu/commit_src.txt 2>/dev/null || cat .gpu/commit.txt 2>/dev/null ||
    git rev-parse --verify -q HEAD 2>/dev/null || echo unknown)"
  [ -f .gpu/commit.txt ] && [ "$(cat .gpu/commit.txt)" != "$commit" ] && commit="$commit (traces made at $(cat .gpu/commit.txt))"
  # Prebuilt binaries: the commit they were built at (and what was uncommitted then).
  [ -f "$WORK/meta/prebuilt_commit.txt" ] && commit="$(cat "$WORK/meta/prebuilt_commit.txt")"
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv,noheader \
    >"$WORK/meta/nvidia_smi.txt" 2>/dev/null || true
  nvcc --version | tail -n 1 >"$WORK/meta/nvcc.txt" 2>/dev/null || true
  # Small per-run files for whoever reads the report (no images: they stay on the machine).
  (cd "$WORK" && find . \( -name '*.json' -o -path './meta/*.txt' \) -not -path './sanitize/*' | tar -cf - -T - |
     xz -6 >"$REPORT_DIR/work_json.tar.xz") || true
  "$BUILD/cuda_ref/cuda_gpu_report" "$WORK" "$REPORT_DIR" "$device" "$commit"
}

phases=("$@")
[ ${#phases[@]} -gt 0 ] || phases=(all)
for ph in "${phases[@]}"; do
  case "$ph" in
    all) phase_build; phase_test; phase_baselines; phase_cross; use_set 4k4; phase_baselines; phase_cross; use_set 1080p
         phase_orbit; phase_sanitize; phase_report ;;
    baselines) phase_baselines ;;
    baselines_4k4) use_set 4k4; phase_baselines; use_set 1080p ;;
    cross_4k4) use_set 4k4; phase_cross; use_set 1080p ;;
    profile) phase_profile ;;
    orbit) phase_orbit ;;
    build) phase_build ;;
    test) phase_test ;;
    cross) phase_cross ;;
    sanitize) phase_sanitize ;;
    report) phase_report ;;
    *) die "unknown phase $ph (all, build, test, baselines, cross, baselines_4k4, cross_4k4, orbit, sanitize, profile, report)" ;;
  esac
done
