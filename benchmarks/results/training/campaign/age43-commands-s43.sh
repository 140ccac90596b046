#!/bin/bash
# forty-third session: early exit capped by age (run.mask_max_age K) on the shipped default,
# on sk-src's 56 validation dancers as deployed (`eval --run`, the mask IoU as deployed new),
# against beta alone and stage 1 on every tick; then the K=6 candidate with presence and depth
# scale refitted under it on sk-mask-mix's 104 validation recordings, as deployed again.
set -eu
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
run56() {  # run56 TAG [eval flags]
  local tag=$1; shift
  $Y eval --weights ${W:-models/default.h5} --data $D/sk-src/val --run --seconds 2.5 --threads ${THREADS:-1} "$@" \
    --poses $D/runs/$tag-s43-run56.csv --json $R/run56-$tag-s43.json > $R/run56-$tag-s43.txt 2>&1
}
if [ "${SWEEP:-1}" = 1 ]; then
  run56 default
  run56 default-b101 --no-early-exit
  for b in 0.95 0.955 0.97 0.98; do run56 default-b$b --beta $b; done
  for k in 8 6 4; do run56 default-age$k --mask-max-age $k; done
  for bk in 0.92:6 0.9:5; do run56 default-b${bk%:*}-age${bk#*:} --beta ${bk%:*} --mask-max-age ${bk#*:}; done
fi
$Y weights combine --mask models/campaign/mask-s36/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
  --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s43-age6.json -o $D/runs/age6-s43.h5
$Y weights calibrate --weights $D/runs/age6-s43.h5 --data $D/sk-mask-mix/val --seconds 2 --beta 0.94 --presence-tau 0.5 \
  --depth-tau 0.5 --depth-without-forearms --threads ${THREADS:-1} -o $D/runs/age6-s43-cal.h5 > $R/calibrate-age6-maskmix-s43.txt 2>&1
W=$D/runs/age6-s43-cal.h5 run56 age6-cal
/usr/bin/python3 benchmarks/training/paired.py --poses --root --common $D/runs/default-s43-run56.csv $D/runs/age6-cal-s43-run56.csv
