#!/usr/bin/env bash
# score_run.sh RUN CONFIG [TAG]: a stage-2 run of the campaign scored as the issue asks, on
# sk-src's 56 validation dancers at the cast's own cue: its final weights combined with the
# shipped stage 1 (or MASK's) under CONFIG's run settings, then `yelan eval` behind stage 1's masks (frame
# by frame, net56-RUN-TAG) and `yelan eval --run`, the deployed path (run56-RUN-TAG, with the
# poses for paired.py --poses). Pair two runs with benchmarks/training/paired.py.
set -euo pipefail
cd "$(dirname "$0")/../.."
run=$1 cfg=$2 tag=${3:-s34}
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan} R=benchmarks/results/training/campaign
mask=${MASK:-models/default.h5} threads=${THREADS:-1}
w=$D/runs/$run-deployed.h5
"$Y" weights combine --mask "$mask" --pose "$D/runs/$run/final.h5" --config "$cfg" -o "$w"
"$Y" eval --weights "$w" --data "$D/sk-src/val" --seconds 2.5 --threads "$threads" --json "$R/net56-$run-$tag.json" > "$R/net56-$run-$tag.txt" 2>&1
"$Y" eval --weights "$w" --data "$D/sk-src/val" --run --seconds 2.5 --threads "$threads" --poses "$D/runs/$run-run56.csv" \
  --json "$R/run56-$run-$tag.json" > "$R/run56-$run-$tag.txt" 2>&1
