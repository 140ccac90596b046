#!/usr/bin/env bash
# candidate.sh TAG [MASK POSE CONFIG]: a candidate default made and scored as deployed on
# validation, the way the defaults since the forty-first session were chosen: stage 1 MASK and
# stage 2 POSE combined under CONFIG, presence and depth scale refitted under its run settings
# on sk-mask-mix's 104 validation recordings (calibrate-TAG), then `yelan eval --run` on
# sk-src's 56 validation dancers (run56-TAG; its poses in $D/runs/TAG-run56.csv). With TAG
# alone: models/default.h5 as it is scored the same way. Pair two with
#   benchmarks/training/paired.py --poses --root --common $D/runs/A-run56.csv $D/runs/B-run56.csv
# The data: benchmarks/training/campaign.sh val-data. Environment: D, Y, THREADS (default 2).
set -euo pipefail
cd "$(dirname "$0")/../.."
tag=$1
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan} R=benchmarks/results/training/campaign
threads=${THREADS:-2}
w=models/default.h5
if [ $# -ge 4 ]; then
  mkdir -p "$D/runs"
  "$Y" weights combine --mask "$2" --pose "$3" --config "$4" -o "$D/runs/$tag.h5"
  w=$D/runs/$tag-cal.h5
  "$Y" weights calibrate --weights "$D/runs/$tag.h5" --data "$D/sk-mask-mix/val" --seconds 2 --beta 0.94 --presence-tau 0.5 \
    --depth-tau 0.5 --depth-without-forearms --threads "$threads" -o "$w" > "$R/calibrate-$tag.txt" 2>&1
fi
"$Y" eval --weights "$w" --data "$D/sk-src/val" --run --seconds 2.5 --threads "$threads" --poses "$D/runs/$tag-run56.csv" \
  --json "$R/run56-$tag.json" > "$R/run56-$tag.txt" 2>&1
tail -n 30 "$R/run56-$tag.txt"
