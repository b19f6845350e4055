#!/usr/bin/env bash
# A whole `tilevis sweep` (golden, truth, the SystemC model and the CUDA reference) on a GPU
# machine that lacks TileVis's build dependencies (Ubuntu 24.04 with CUDA 13 and python3 with
# matplotlib; no SystemC, OpenEXR, assimp, meshes or network). The binary built here travels
# with the shared libraries it needs and the meshes the scenes read.
#
#   bash cuda_ref/sweep_on_gpu.sh prepare [--tests] HERE, after a full build (./tilevis demo or test):
#                                                  fills .gpusweep/ (git-ignored): bin/tilevis, lib/, the
#                                                  meshes the built-in scenes name (meshes/{glmark2,cgal}/,
#                                                  meshes/root/ for absolute paths), commit.txt; --tests adds
#                                                  cuda_gpu_tests (for bench; 11 MB of the 64 MiB a call carries);
#                                                  captured.tar.xz: the captured OpenGL workloads (the .tvt files of
#                                                  $TILEVIS_CAPTURED, default reports/demo/captured, captured there
#                                                  first when it holds none and xvfb-run and glmark2 are present;
#                                                  19 MB of traces, 3 MB compressed)
#   bash cuda_ref/sweep_on_gpu.sh run SWEEP NAME   THERE, from the repository root with .gpusweep
#                                                  carried: tilevis sweep SWEEP -o reports/NAME -j nproc,
#                                                  stopped cleanly (SIGINT) after TILEVIS_SWEEP_SECONDS
#                                                  (default 500) so that the machine's command limit
#                                                  never cuts a point in half; run it again to go on
#                                                  (finished points are kept while the machine is warm);
#                                                  the carried captured traces go to reports/NAME/captured, the
#                                                  folder reference.json's and demo.json's "captured" set names
#
#   bash cuda_ref/sweep_on_gpu.sh bench SCENE...   THERE, likewise: cuda_ref's GPU tests (the carried
#                                                  cuda_gpu_tests), then `tilevis cuda` exact and float
#                                                  at tiles $TILEVIS_BENCH_TILES (default 32) on each
#                                                  scene (traced there), 20 timed runs; TILEVIS_NCU=1
#                                                  adds Nsight Compute's time per kernel for the first
#                                                  scene in float. A table of total and stage times last;
#                                                  $OUT/bench.json holds every stats.json.
#
# `run` leaves in $OUT: NAME-report.tar.xz (index.html, report.md, points.csv, figures/, sweep.json,
# best_tiles.*: what reports/NAME/ commits) and NAME-points.tar.xz.partNN (every point's JSON, CSV
# and logs, no EXR or traces, plus the captured .tvt files in NAME/captured, which the sweep reads
# to plan their points: enough for `tilevis sweep SWEEP -o reports/NAME --report-only` here).
# CUDA points hold the producer-level resource "gpu", so one runs at a time and its timings are
# its own; the CPU producers fill the other cores meanwhile.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
CARRY=.gpusweep
say() { printf '\033[1msweep_on_gpu:\033[0m %s\n' "$*" >&2; }
die() { say "error: $*"; exit 1; }

prepare() {
  local bin=build/model/app/tilevis
  [ -x "$bin" ] || die "$bin missing: build first (./tilevis demo)"
  "$bin" cuda --help >/dev/null 2>&1 || die "$bin has no CUDA reference (configure with nvcc on PATH)"
  rm -rf "$CARRY" && mkdir -p "$CARRY/bin" "$CARRY/lib" "$CARRY/meshes"
  cp "$bin" "$CARRY/bin/"
  if [ "${1:-}" = --tests ]; then
    cp build/tests/cuda/cuda_gpu_tests "$CARRY/bin/" || die "build/tests/cuda/cuda_gpu_tests missing: build the tests"
  fi
  # Every shared library but the C runtime and libstdc++/libgcc (the target's are newer and compatible).
  ldd "$bin" | awk '$3 ~ /^\// {print $3}' | while read -r lib; do
    case "$(basename "$lib")" in
      libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | ld-linux* | libstdc++.so* | libgcc_s.so*) ;;
      *) cp -L "$lib" "$CARRY/lib/" ;;
    esac
  done
  # The meshes the built-in scenes name: glmark2/ and cgal/ are found through TILEVIS_GLMARK2_MODELS and
  # TILEVIS_CGAL_MESHES (traces/gen/CMakeLists.txt); an absolute path goes under meshes/root/, which
  # `run` links into place.
  local glmark=/usr/share/glmark2/models cgal=build/data/cgal mesh
  grep -ho '"mesh": *"[^"]*"' traces/scenes/*.json | sed 's/.*: *"\(.*\)"/\1/' | sort -u | while read -r mesh; do
    case "$mesh" in
      glmark2/*) install -D -m 644 "$glmark/${mesh#glmark2/}" "$CARRY/meshes/$mesh" ;;
      cgal/*) install -D -m 644 "$cgal/${mesh#cgal/}" "$CARRY/meshes/$mesh" ;;
      /*) install -D -m 644 "$mesh" "$CARRY/meshes/root$mesh" ;;
      *) ;;  # beside the scene file: travels with the working tree
    esac || die "mesh $mesh missing: build first (./tilevis demo)"
  done
  carry_captured
  git rev-parse --short HEAD >"$CARRY/commit.txt"
  [ -z "$(git status --porcelain --untracked-files=no)" ] || sed -i 's/$/-dirty/' "$CARRY/commit.txt"
  grep -qx "/$CARRY/" .git/info/exclude 2>/dev/null || grep -qx "/$CARRY/" .gitignore ||
    echo "/$CARRY/" >>.git/info/exclude
  say "$(du -sh "$CARRY" | cut -f1) in $CARRY/ (commit $(cat "$CARRY/commit.txt")): carry [\"$CARRY\"]"
}

# The captured OpenGL workloads (traces/capture) for the sweeps' "captured" trace sets: the GPU
# machine has no Xvfb or glmark2, so they are captured here and carried, compressed.
carry_captured() {
  local dir="${TILEVIS_CAPTURED:-reports/demo/captured}"
  if ! ls "$dir"/*.tvt >/dev/null 2>&1; then
    if command -v xvfb-run >/dev/null && command -v glmark2 >/dev/null; then
      say "no captured traces in $dir: capturing glmark2 and neverball there (about a minute)"
      SIMULATE=0 traces/capture/capture_workloads.sh "$dir" build/model/app/tilevis >"$dir.log" 2>&1 ||
        say "capture_workloads.sh failed: see $dir.log"
    fi
  fi
  if ls "$dir"/*.tvt >/dev/null 2>&1; then
    (cd "$dir" && ls ./*.tvt | tar -cf - -T - | xz -6 -T0) >"$CARRY/captured.tar.xz"
    say "captured workloads: $(ls "$dir"/*.tvt | wc -l) traces from $dir ($(du -ch "$dir"/*.tvt | tail -n 1 | cut -f1)," \
        "$(du -h "$CARRY/captured.tar.xz" | cut -f1) compressed)"
  else
    say "WARNING: no captured traces in $dir and no xvfb-run/glmark2 here to make them: a sweep there will list" \
        "its captured workloads as missing (make them with traces/capture/capture_workloads.sh $dir)"
  fi
}

# The carried captured traces into reports/NAME/captured (kept if that folder already holds traces).
unpack_captured() {
  local dir="reports/$1/captured"
  if [ -f "$CARRY/captured.tar.xz" ]; then
    ls "$dir"/*.tvt >/dev/null 2>&1 || { mkdir -p "$dir" && xz -dc "$CARRY/captured.tar.xz" | tar -C "$dir" -xf -; }
    say "captured workloads: $(ls "$dir"/*.tvt | wc -l) traces in $dir"
  else
    say "WARNING: no captured traces carried ($CARRY/captured.tar.xz): the sweep lists its captured workloads as missing"
  fi
}

# Meshes the scenes name by absolute path (Debian's assimp-testmodels), linked into place where missing.
link_absolute_meshes() {
  [ -d "$CARRY/meshes/root" ] || return 0
  (cd "$CARRY/meshes/root" && find . -type f) | while read -r f; do
    [ -e "/${f#./}" ] || { mkdir -p "$(dirname "/${f#./}")" && ln -s "$ROOT/$CARRY/meshes/root/${f#./}" "/${f#./}"; } ||
      say "could not link /${f#./}: scenes that name it will fail"
  done
}

run() {
  local sweep="${1:?usage: sweep_on_gpu.sh run SWEEP NAME}" name="${2:?usage: sweep_on_gpu.sh run SWEEP NAME}"
  [ -x "$CARRY/bin/tilevis" ] || die "$CARRY/ missing: run 'sweep_on_gpu.sh prepare' on the build machine and carry it"
  local out="${OUT:-/tmp/sweep_out}" dir="reports/$name" rc=0
  mkdir -p "$out"
  export LD_LIBRARY_PATH="$ROOT/$CARRY/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export TILEVIS_SOURCE_DIR="$ROOT" TILEVIS_COMMIT="$(cat "$CARRY/commit.txt")"
  export TILEVIS_GLMARK2_MODELS="$ROOT/$CARRY/meshes/glmark2" TILEVIS_CGAL_MESHES="$ROOT/$CARRY/meshes/cgal"
  link_absolute_meshes
  unpack_captured "$name"
  export TILEVIS_PYTHON="${TILEVIS_PYTHON:-$(command -v python3)}"
  "$TILEVIS_PYTHON" -c "import matplotlib, numpy" || die "$TILEVIS_PYTHON lacks matplotlib or numpy"
  nvidia-smi -L || say "no nvidia-smi: the CUDA points will be reported unavailable"
  say "tilevis sweep $sweep -o $dir -j $(nproc), for at most ${TILEVIS_SWEEP_SECONDS:-500} s"
  timeout -s INT "${TILEVIS_SWEEP_SECONDS:-500}" "$CARRY/bin/tilevis" sweep "$sweep" -o "$dir" -j "$(nproc)" || rc=$?
  if [ "$rc" = 124 ] || [ "$rc" = 130 ]; then
    say "stopped after ${TILEVIS_SWEEP_SECONDS:-500} s: run the same command again to finish the rest"
    "$CARRY/bin/tilevis" sweep "$sweep" -o "$dir" --report-only || true
  fi
  tar -C reports -cJf "$out/$name-report.tar.xz" \
    --exclude="$name/points" --exclude="$name/traces" --exclude="$name/captured" "$name"
  local captured=()
  [ -d "reports/$name/captured" ] && captured=("$name/captured")
  tar -C reports -cf - --exclude='*.exr' --exclude='*.bin' --exclude="$name/traces" "$name/points" "${captured[@]}" |
    xz -6 -T0 | split -b 15M -d - "$out/$name-points.tar.xz.part"
  ls -la "$out"
  return "$rc"
}

bench() {
  [ $# -ge 1 ] || die "usage: sweep_on_gpu.sh bench SCENE..."
  [ -x "$CARRY/bin/tilevis" ] || die "$CARRY/ missing: run 'sweep_on_gpu.sh prepare' on the build machine and carry it"
  local out="${OUT:-/tmp/bench_out}" work=/tmp/tilevis_bench rc=0
  mkdir -p "$out" "$work"
  export LD_LIBRARY_PATH="$ROOT/$CARRY/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export TILEVIS_SOURCE_DIR="$ROOT" TILEVIS_COMMIT="$(cat "$CARRY/commit.txt")"
  export TILEVIS_GLMARK2_MODELS="$ROOT/$CARRY/meshes/glmark2" TILEVIS_CGAL_MESHES="$ROOT/$CARRY/meshes/cgal"
  link_absolute_meshes
  export PATH="/usr/local/cuda/bin:$PATH"
  nvidia-smi -L || die "no GPU here"
  if [ -x "$CARRY/bin/cuda_gpu_tests" ]; then
    "$CARRY/bin/cuda_gpu_tests" --gtest_brief=1 >"$out/gpu_tests.log" 2>&1 || rc=$?
    say "cuda_gpu_tests: exit $rc, $(grep -cE '^\[  (FAILED|SKIPPED) ' "$out/gpu_tests.log") failed or skipped lines"
    tail -n 3 "$out/gpu_tests.log" >&2
  fi
  for scene in "$@"; do
    "$CARRY/bin/tilevis" trace "traces/scenes/$scene.json" -q -o "$work/$scene.tvt" || die "trace $scene failed"
    for tile in ${TILEVIS_BENCH_TILES:-32}; do
      for prec in exact float; do
        "$CARRY/bin/tilevis" cuda "$work/$scene.tvt" --tile "$tile" --precision "$prec" -o "$work/$scene-$tile-$prec" \
          >"$work/$scene-$tile-$prec.log" 2>&1 || { rc=1; say "cuda $scene $tile $prec failed"; tail -n 5 "$work/$scene-$tile-$prec.log" >&2; }
      done
    done
  done
  if [ "${TILEVIS_NCU:-0}" = 1 ] && command -v ncu >/dev/null; then
    ncu --metrics gpu__time_duration.sum --csv "$CARRY/bin/tilevis" cuda "$work/$1.tvt" --tile 32 --precision float \
      --runs 1 --warmup 1 -o "$work/ncu_run" >"$out/ncu.csv" 2>"$out/ncu.log" || say "ncu failed (see ncu.log)"
  fi
  python3 - "$work" "$out" <<'PY'
import csv, glob, json, os, sys
work, out = sys.argv[1], sys.argv[2]
runs = {}
for f in sorted(glob.glob(os.path.join(work, "*", "stats.json"))):
    runs[os.path.basename(os.path.dirname(f))] = json.load(open(f))
json.dump(runs, open(os.path.join(out, "bench.json"), "w"), indent=1)
ncu = os.path.join(out, "ncu.csv")
if os.path.exists(ncu):
    per = {}
    lines = [l for l in open(ncu) if l.startswith('"')]
    for r in csv.DictReader(lines):
        if r.get("Metric Name") != "gpu__time_duration.sum": continue
        name = r["Kernel Name"].split("(")[0].split("<")[0].split("::")[-1][:40]
        v = float(r["Metric Value"].replace(",", "")) / (1000.0 if r["Metric Unit"] == "nsecond" else 1.0)
        per[name] = per.get(name, 0.0) + v
    print("ncu, first scene float, one warm run (us per kernel, summed over launches):")
    for k, v in sorted(per.items(), key=lambda kv: -kv[1])[:25]:
        print(f"  {v:9.1f}  {k}")
    print(f"  {sum(per.values()):9.1f}  total")
stages = ["setup", "silhouettes", "binning", "cull", "clip", "occlusion", "raster", "unclipped_pieces"]
print("run (ms)                  graph  " + " ".join(f"{s[:7]:>7}" for s in stages) + "   stream   ops syncs")
for name, d in runs.items():
    st = d["stage_ms"]
    print(f"{name:24s} {d['total_ms']:7.3f}  " + " ".join(f"{st.get(s, 0):7.3f}" for s in stages) +
          f"  {d.get('stream_total_ms', 0):7.3f}  {d.get('queued_operations', 0):4d} {d.get('host_syncs', 0):5d}")
PY
  return "$rc"
}

case "${1:-}" in
  prepare) shift; prepare "$@" ;;
  run) shift; run "$@" ;;
  bench) shift; bench "$@" ;;
  *) die "usage: sweep_on_gpu.sh prepare | run SWEEP NAME | bench SCENE..." ;;
esac
