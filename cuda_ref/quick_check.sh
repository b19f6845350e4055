#!/usr/bin/env bash
# One GPU call that builds, tests and times the tree as it is (gpu_run.sh's build and test
# phases), then packs the binaries it built for later calls (TILEVIS_GPU_PREBUILT=1):
#
#   bash cuda_ref/quick_check.sh [build] [base] [test] [emulation] [gl] [bench] [sanitize] [pack]   (default: all but base, gl and sanitize)
#
# bench: `tilevis cuda` at 32x32 tiles, TILEVIS_QUICK_RUNS runs (default 10), on the scenes of
# TILEVIS_QUICK_SCENES (default "bunny million slivers"), exact and float, with both CUDA
# z-buffers timed in the same process; a table of new frame (device-sized graph), stream (sizes
# read on the host), presized, graph and the ratios to the z-buffers, last. A/B of environment
# switches: TILEVIS_QUICK_VARIANTS="off:TILEVIS_CUDA_PDL=off exit:TILEVIS_CUDA_PDL=exit" runs every
# scene and precision under each NAME:VAR=VALUE[,VAR=VALUE...] in turn (interleaved, TILEVIS_QUICK_PASSES times,
# default 1), checks that ids.exr, tiles.csv and visible_area.bin are the same bytes under every
# variant, and tables each variant's times, then the variants side by side, each against the first
# (cuda_ref/tools/bench_table.py; over GL too where phase gl ran). A variant may run another build's tool:
# TILEVIS_QUICK_BIN=PATH among its assignments. Phase `base` builds the tree of every
# .gpu/NAME_src.tar.xz (`git archive REV | xz >.gpu/NAME_src.tar.xz` on the sender) beside this
# one, in /tmp/NAME_src, and runs its GPU tests (label gpu; not base's), so that
# "base:TILEVIS_QUICK_BIN=/tmp/base_src/build-gpu/model/app/tilevis new:" compares a change with
# the commit before it, outputs byte for byte, and more trees (other branches) can be timed in
# the same call. It also unpacks every .gpu/NAME_bin.tar.xz (a tilevis built on the sender,
# `prepare_gpu_run.sh --bin NAME DIR`) as /tmp/NAME_bin/tilevis, which compiles nothing there: with
# TILEVIS_GPU_PREBUILT=1, "base:TILEVIS_QUICK_BIN=/tmp/base_bin/tilevis new:" times a change built
# here against the commit before it at no build time on the GPU machine. Phase `gl` (before bench; .gl carried)
# times the GPU's own rasteriser (gl_raster --runs 20) on the same scenes, and the bench table
# then gives each run's new frame over it (/ GL). With .gpu carried
# (prepare_gpu_run.sh) and the commit in .gpu/commit_src.txt (the sender writes it). $OUT gets
# bench.json (every stats.json), prebuilt.tar.xz (pack) and gpu_run.sh's logs.tar.xz.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT" || exit 1
OUT="${OUT:-/tmp/quick_out}"
export OUT
mkdir -p "$OUT"
# The carried libraries (gpu_run.sh build unpacks them there), for the runs outside gpu_run.sh.
export LD_LIBRARY_PATH="/tmp/sysroot/usr/lib/x86_64-linux-gnu:/tmp/sysroot/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
BUILD="$ROOT/build-gpu"
BIN="$BUILD/model/app/tilevis"
phases=("$@")
[ ${#phases[@]} -gt 0 ] || phases=(build test emulation bench pack)
t0=$SECONDS
say() { printf 'quick_check [%4d s]: %s\n' "$((SECONDS - t0))" "$*" >&2; }
for ph in "${phases[@]}"; do
  # Prebuilt binaries (TILEVIS_GPU_PREBUILT=1: the build phase unpacks them) and the tools run
  # beside them find their libraries there.
  if [ -d "$BUILD/prebuilt_lib" ] && [[ ":${LD_LIBRARY_PATH}:" != *":$BUILD/prebuilt_lib:"* ]]; then
    export LD_LIBRARY_PATH="$BUILD/prebuilt_lib:$LD_LIBRARY_PATH"
  fi
  case "$ph" in
    build) bash cuda_ref/gpu_run.sh build 2>&1 | tail -n 4; say "build done" ;;
    test)
      TILEVIS_TEST_LABEL=gpu bash cuda_ref/gpu_run.sh test 2>&1 | tail -n 25
      say "GPU tests: $(cat "$BUILD/work/meta/gpu_tests.txt" 2>/dev/null)" ;;
    emulation)
      ctest --test-dir "$BUILD" -L cuda -j "$(nproc)" --output-on-failure >"$OUT/emulation.log" 2>&1
      say "host emulation tests: $(grep -E 'tests passed|tests failed' "$OUT/emulation.log" | tail -n 1)"
      grep -E "\*\*\*Failed|FAILED" "$OUT/emulation.log" | head -n 20 ;;
    base)
      for tarball in .gpu/*_bin.tar.xz; do
        [ -f "$tarball" ] || break
        dir="/tmp/$(basename "$tarball" .tar.xz)"
        rm -rf "$dir" && mkdir -p "$dir" && tar -C "$dir" -xJf "$tarball"
        if "$dir/tilevis" cuda --help 2>/dev/null | grep -q precision; then
          say "$(basename "$tarball"): $dir/tilevis"
        else
          say "$(basename "$tarball"): $dir/tilevis does not run here: $("$dir/tilevis" cuda --help 2>&1 | tail -n 1)"
        fi
      done
      for tarball in .gpu/*_src.tar.xz; do
        [ -f "$tarball" ] || { say "no .gpu/NAME_src.tar.xz to build"; break; }
        name="$(basename "$tarball" _src.tar.xz)" dir="/tmp/$(basename "$tarball" .tar.xz)"
        rm -rf "$dir" && mkdir -p "$dir" && tar -C "$dir" -xJf "$tarball" && ln -s "$ROOT/.gpu" "$dir/.gpu" &&
          (cd "$dir" && OUT="/tmp/${name}_out" bash cuda_ref/gpu_run.sh build 2>&1 | tail -n 2)
        say "$name build done: $(ls "$dir/build-gpu/model/app/tilevis" 2>&1)"
        [ "$name" = base ] && continue  # the reference: its tests ran where it was committed
        log="/tmp/${name}_gpu_tests.log"
        TILEVIS_GPU_TRACES="$dir/build-gpu/gpu_traces" ctest --test-dir "$dir/build-gpu" -L gpu -j 4 \
          --output-on-failure >"$log" 2>&1
        say "$name GPU tests: $(grep -E 'tests passed|tests failed' "$log" | tail -n 1)"
        grep -E "\*\*\*Failed|FAILED" "$log" | head -n 20
      done ;;
    gl)
      if [ -d .gl ] && ! ldconfig -p | grep -q libEGL.so.1; then
        for f in .gl/*.deb; do dpkg -x "$f" /; done
        ldconfig
      fi
      vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
      [ -f "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"
      rm -rf /tmp/quick_gl && mkdir -p /tmp/quick_gl
      for s in ${TILEVIS_QUICK_SCENES:-bunny million slivers}; do
        "$BUILD/cuda_ref/gl_raster" "$BUILD/gpu_traces/$s.tvt" --runs 20 -o "/tmp/quick_gl/$s" >"/tmp/quick_gl/$s.log" 2>&1 ||
          say "gl_raster $s failed: $(tail -n 2 "/tmp/quick_gl/$s.log")"
      done
      python3 - "$OUT/gl.json" <<'PY'
import glob, json, os, sys
rows = {os.path.basename(os.path.dirname(f)): json.load(open(f)) for f in sorted(glob.glob("/tmp/quick_gl/*/stats.json"))}
json.dump(rows, open(sys.argv[1], "w"), indent=1)
print(" ".join(f"{k} {v['hw_raster_ms']:.3f} ms" for k, v in rows.items()))
PY
      say "GL timed" ;;
    sanitize)
      bash cuda_ref/gpu_run.sh sanitize 2>&1 | tail -n 20
      say "sanitizers: $(cat "$BUILD/work/meta/sanitizer.txt" 2>/dev/null)" ;;
    bench)
      rm -rf /tmp/quick && mkdir -p /tmp/quick
      variants=(${TILEVIS_QUICK_VARIANTS:-})
      [ ${#variants[@]} -gt 0 ] || variants=("")
      run_name() { # scene precision variant pass
        local n="$1_$2"
        [ -n "$3" ] && n="${n}_${3%%:*}"
        [ "$4" = 1 ] || n="${n}_pass$4"
        echo "$n"
      }
      compared=0 differ=0
      for pass in $(seq 1 "${TILEVIS_QUICK_PASSES:-1}"); do
        for s in ${TILEVIS_QUICK_SCENES:-bunny million slivers}; do
          for p in ${TILEVIS_QUICK_PRECISIONS:-float exact}; do
            for v in "${variants[@]}"; do
              name="$(run_name "$s" "$p" "$v" "$pass")"
              assigns=()
              [ -n "$v" ] && IFS=',' read -ra assigns <<<"${v#*:}"
              bin="$BIN" envs=()
              for as in "${assigns[@]}"; do
                case "$as" in TILEVIS_QUICK_BIN=*) bin="${as#*=}" ;; ?*) envs+=("$as") ;; esac
              done
              env "${envs[@]}" "$bin" cuda "$BUILD/gpu_traces/$s.tvt" --tile 32 --precision "$p" \
                --runs "${TILEVIS_QUICK_RUNS:-10}" ${TILEVIS_QUICK_ARGS:-} -o "/tmp/quick/$name" >"/tmp/quick/$name.log" 2>&1 ||
                say "cuda $name failed: $(tail -n 2 "/tmp/quick/$name.log")"
            done
            # Every variant's outputs against the first's, byte for byte.
            first="$(run_name "$s" "$p" "${variants[0]}" "$pass")"
            for v in "${variants[@]:1}"; do
              other="$(run_name "$s" "$p" "$v" "$pass")"
              for f in ids.exr tiles.csv visible_area.bin; do
                [ -f "/tmp/quick/$first/$f" ] || continue
                compared=$((compared + 1))
                cmp -s "/tmp/quick/$first/$f" "/tmp/quick/$other/$f" ||
                  { differ=$((differ + 1)); say "OUTPUT DIFFERS: $other/$f against $first/$f"; }
              done
            done
          done
        done
      done
      python3 - "$OUT/bench.json" <<'PY'
import glob, json, os, sys
rows = {}
for f in sorted(glob.glob("/tmp/quick/*/stats.json")):
    rows[os.path.basename(os.path.dirname(f))] = json.load(open(f))
json.dump(rows, open(sys.argv[1], "w"), indent=1)
def gl_ms(run):  # phase gl's time of the run's scene (the longest scene name that prefixes it)
    names = [n for n in os.listdir("/tmp/quick_gl") if run.startswith(n + "_")] if os.path.isdir("/tmp/quick_gl") else []
    f = f"/tmp/quick_gl/{max(names, key=len)}/stats.json" if names else ""
    return json.load(open(f))["hw_raster_ms"] if f and os.path.exists(f) else float("nan")
print("| run | new frame ms | stream | presized | graph | tiled zb ms | naive zb ms | / tiled | / naive | GL ms | / GL | retries |")
for k, s in rows.items():
    g = lambda key: s.get(key, float("nan"))
    gl = gl_ms(k)
    print(f"| {k} | {g('total_ms'):.3f} | {g('stream_total_ms'):.3f} | {g('presized_total_ms'):.3f} | "
          f"{g('graph_total_ms'):.3f} | {g('cuda_zbuffer_ms'):.3f} | {g('naive_zbuffer_ms'):.3f} | "
          f"{g('cuda_zbuffer_ratio'):.2f} | {g('naive_zbuffer_ratio'):.2f} | {gl:.3f} | {g('total_ms') / gl:.2f} | {g('retries')} |")
PY
      # Two variants or more: side by side, each against the first (and over GL where phase gl ran).
      if [ ${#variants[@]} -gt 1 ]; then
        names="$(printf '%s\n' "${variants[@]}" | sed 's/:.*//' | paste -sd, -)"
        gl_args=()
        [ -f "$OUT/gl.json" ] && gl_args=(--gl "$OUT/gl.json")
        python3 cuda_ref/tools/bench_table.py "$OUT/bench.json" --variants "$names" "${gl_args[@]}"
        # Last, so that a caller reading only the tail of the output still sees it.
        say "outputs against the first variant: $compared files compared, $differ differ"
      fi
      ;;
    pack)
      rm -rf /tmp/prebuilt && mkdir -p /tmp/prebuilt/prebuilt/bin /tmp/prebuilt/prebuilt/lib
      for b in model/app/tilevis tests/cuda/cuda_gpu_tests cuda_ref/gl_raster cuda_ref/cuda_gpu_report; do
        install -D -m 755 "$BUILD/$b" "/tmp/prebuilt/prebuilt/bin/$b"
      done
      for b in model/app/tilevis tests/cuda/cuda_gpu_tests cuda_ref/gl_raster; do
        ldd "$BUILD/$b" | awk '$3 ~ /^\// {print $3}'
      done | sort -u | while read -r lib; do
        case "$(basename "$lib")" in
          libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libstdc++.so* | libgcc_s.so* | libcuda.so* | libnvidia*) ;;
          *) cp -L "$lib" /tmp/prebuilt/prebuilt/lib/ ;;
        esac
      done
      echo "$(cat .gpu/commit_src.txt 2>/dev/null || echo unknown) (built on the GPU machine)" >/tmp/prebuilt/prebuilt/commit.txt
      tar -C /tmp/prebuilt -cf - prebuilt | xz -6 -T0 >"$OUT/prebuilt.tar.xz"
      say "packed $(du -sh "$OUT/prebuilt.tar.xz" | cut -f1)" ;;
    *) say "unknown phase $ph" ;;
  esac
done
