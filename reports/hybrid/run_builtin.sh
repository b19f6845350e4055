#!/bin/bash
# Regenerates reports/hybrid/builtin_scenes.md's data: traces of traces/scenes/*.json in $TRACES (default /tmp/traces/traces), results in /tmp/ha.
T="$(cd "$(dirname "$0")/../.." && pwd)/build/model/app/tilevis"
cd "${TRACES:-/tmp/traces/traces}"
for sc in bunny dragon armadillo armadillo_box elephant dragon_bunnies teapot_stadium stack million; do
  for spp in 1 4; do
    $T golden $sc.tvt --samples $spp --truth -o /tmp/ha/$sc/s$spp/truth > /dev/null 2>&1 || echo "$sc truth failed"
    for t in 8 32 128; do
      start=$(date +%s.%N)
      line=$($T golden $sc.tvt --samples $spp --tile $t --mode hybrid -o /tmp/ha/$sc/s$spp/h$t 2>&1 | tail -1)
      end=$(date +%s.%N)
      agr=$($T compare /tmp/ha/$sc/s$spp/h$t /tmp/ha/$sc/s$spp/truth 2>&1 | grep "sample agreement" | head -1)
      echo "$sc spp=$spp tile=$t | $agr | $line | $(echo "$end - $start" | bc) s"
    done
  done
done
