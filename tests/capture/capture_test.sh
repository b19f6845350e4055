#!/bin/sh
# Captures two frames of glmark2's build scene under Xvfb (Mesa llvmpipe, no GPU) and checks
# the trace against what is known without the capture:
#   - each frame holds the horse model's triangles: the count the scene generator reads from
#     glmark2-data's horse.3ds (assimp), the mesh the scene draws;
#   - its one draw is opaque (the scene draws with depth test and writes, no blending);
#   - the application's own depth buffer agrees with the exact truth's depth of the trace on
#     at least 99.9 % of the covered pixels of each frame;
#   - golden and the truth take the trace, and hybrid equals the truth on it;
#   - with --offscreen, glmark2's shadow scene gives two passes: the shadow map (a framebuffer
#     object: the horse alone) and the window (the horse and its ground), each within 99.9 %.
# Usage: capture_test.sh TILEVIS WORKDIR
set -eu
tilevis=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
unset DISPLAY  # always under Xvfb: the same software renderer wherever the test runs

"$tilevis" capture --frames 2 --skip 2 --timeout 120 -o "$work/build.tvt" -- glmark2 -b build:duration=30

# The expected count, independent of the capture: the mesh file itself.
cat > "$work/horse.json" <<JSON
{"viewport": [800, 600], "camera": {"eye": [0, 0, 5], "target": [0, 0, 0], "fov_y_deg": 45, "near": 0.1, "far": 100},
 "objects": [{"name": "horse", "mesh": "/usr/share/glmark2/models/horse.3ds"}]}
JSON
"$tilevis" trace "$work/horse.json" -o "$work/horse.tvt" >/dev/null
expected=$("$tilevis" info "$work/horse.tvt" --summary | sed -n 's/.* \([0-9][0-9]*\) triangles.*/\1/p')
[ -n "$expected" ] || { echo "FAIL: no triangle count for horse.3ds"; exit 1; }

"$tilevis" info "$work/build.tvt" --max-draws 10 > "$work/info.txt"
cat "$work/info.txt"
frames=$(grep -c '^frame [0-9]*:' "$work/info.txt")
[ "$frames" -eq 2 ] || { echo "FAIL: $frames frames, expected 2"; exit 1; }
counts=$(sed -n 's/^ *\([0-9]*\) draws, \([0-9]*\) triangles.*/\1 \2/p' "$work/info.txt")
echo "$counts" | while read -r draws triangles; do
  [ "$draws" -eq 1 ] || { echo "FAIL: $draws draws in a frame, expected 1"; exit 1; }
  [ "$triangles" -eq "$expected" ] || { echo "FAIL: $triangles triangles in a frame, horse.3ds has $expected"; exit 1; }
done
[ "$(echo "$counts" | wc -l)" -eq 2 ] || { echo "FAIL: per-frame counts missing"; exit 1; }
# Flags: the draw rows name their flags; none may be non-opaque or per-pixel.
if grep -E '^ *glDraw' "$work/info.txt" | grep -Eq 'blended|alpha_tested|discards|writes_depth'; then
  echo "FAIL: a draw of the build scene is flagged non-opaque or per-pixel"; exit 1
fi
grep -Eq '^ *glDraw.*opaque|^ *glDraw.*soup' "$work/info.txt" || { echo "FAIL: no opaque draw listed"; exit 1; }

"$tilevis" compare-depth "$work/build.tvt" --min-agreement 0.999 -o "$work/depth.json"

"$tilevis" golden "$work/build.tvt" --truth -o "$work/truth" >/dev/null
"$tilevis" golden "$work/build.tvt" --mode hybrid -o "$work/hybrid" >/dev/null
"$tilevis" compare "$work/hybrid" "$work/truth" -o "$work/cmp" >/dev/null
python3 -c "
import json, sys
c = json.load(open('$work/cmp/compare.json'))
print('hybrid vs truth: sample_agreement', c['sample_agreement'])
sys.exit(0 if c['sample_agreement'] == 1.0 else 1)"
# Off-screen passes.
"$tilevis" capture --offscreen --frames 1 --skip 2 --timeout 120 -o "$work/shadow.tvt" -- glmark2 -b shadow:duration=30
"$tilevis" info "$work/shadow.tvt" --max-draws 10 > "$work/shadow_info.txt"
set -- $(sed -n 's/^ *\([0-9]*\) draws, \([0-9]*\) triangles.*/\2/p' "$work/shadow_info.txt")
[ "$#" -eq 2 ] || { echo "FAIL: $# passes in the shadow scene, expected 2"; exit 1; }
[ "$1" -eq "$expected" ] || { echo "FAIL: shadow map pass has $1 triangles, horse.3ds has $expected"; exit 1; }
[ "$2" -gt "$expected" ] || { echo "FAIL: window pass has $2 triangles, expected the horse and more"; exit 1; }
python3 -c "
import json, sys
p = json.load(open('$work/shadow.tvt.capture.json'))['passes']
print('passes:', [(x['framebuffer'], x['width'], x['height']) for x in p])
sys.exit(0 if p[0]['framebuffer'] != 0 and p[1]['framebuffer'] == 0 else 1)"
"$tilevis" compare-depth "$work/shadow.tvt" --min-agreement 0.999
echo PASS
