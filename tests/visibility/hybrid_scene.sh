#!/usr/bin/env bash
# One CTest step: a failure scene through the CLI as a user runs it.
#   hybrid_scene.sh TILEVIS SCENE.json WORKDIR TILE...
# trace, z-buffer truth, then golden --mode hybrid at each tile size: every sample must equal
# the truth's (tilevis compare), and analytic alone is reported beside it.
set -euo pipefail
bin=$1 scene=$2 work=$3
shift 3
name=$(basename "$scene" .json)
dir="$work/$name"
rm -rf "$dir" && mkdir -p "$dir"
"$bin" trace "$scene" -q -o "$dir/$name.tvt"
"$bin" golden "$dir/$name.tvt" --truth -o "$dir/truth" >/dev/null
for tile in "$@"; do
  "$bin" golden "$dir/$name.tvt" --tile "$tile" -o "$dir/analytic_$tile" >/dev/null
  "$bin" golden "$dir/$name.tvt" --tile "$tile" --mode hybrid -o "$dir/hybrid_$tile" | tail -1
  echo "analytic at $tile: $("$bin" compare "$dir/analytic_$tile" "$dir/truth" | grep 'sample agreement')"
  "$bin" compare "$dir/hybrid_$tile" "$dir/truth" >/dev/null
  python3 - "$dir/hybrid_$tile/compare.json" "$name" "$tile" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
if c["mismatched_samples"] != 0:
    sys.exit(f"hybrid_scene: {sys.argv[2]} at {sys.argv[3]}: {c['mismatched_samples']} samples differ from the truth")
print(f"hybrid at {sys.argv[3]}: 0 of {c['samples_compared']} samples differ from the truth")
PY
done
