#!/usr/bin/env bash
# reused_cut_sweep.sh: a screening of run.mask_cut_reused (VALUES, default 0.25 0.3 0.4 0.45) under
# the -s44 default, no refit: mask IoU as deployed, root-aligned MPJPE and the paired difference
# against the shipped cut 0.35 (needs $D/runs/mask-s43-age6-s44-run56.csv from candidate.sh) on
# sk-src's 56 validation dancers. Choose on validation only.
set -euo pipefail
cd "$(dirname "$0")/../.."
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan}
mkdir -p $D/cuts
for v in ${VALUES:-0.25 0.3 0.4 0.45}; do
  python3 -c "
import json,sys
c=json.load(open('benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s44.json'))
c['run']['mask_cut_reused']=$v
json.dump(c,open('$D/cuts/cfg-$v.json','w'))"
  $Y weights combine --mask models/campaign/mask-s43/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 --config $D/cuts/cfg-$v.json -o $D/cuts/w-$v.h5 > /dev/null
  $Y eval --weights $D/cuts/w-$v.h5 --data $D/sk-src/val --run --seconds 2.5 --threads 2 --poses $D/cuts/run56-$v.csv --json $D/cuts/run56-$v.json > $D/cuts/run56-$v.txt 2>&1
  echo "cut_reused $v: $(grep -o 'root-aligned [0-9.]* mm, PCK' $D/cuts/run56-$v.txt | head -1) $(grep -o 'reused): [0-9.]*' $D/cuts/run56-$v.txt) $(grep -o 'stage 1 on [0-9]*% of ticks' $D/cuts/run56-$v.txt)"
  /usr/bin/python3 benchmarks/training/paired.py --poses --root --common $D/runs/mask-s43-age6-s44-run56.csv $D/cuts/run56-$v.csv | tail -1
done
