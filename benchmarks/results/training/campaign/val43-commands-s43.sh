#!/bin/bash
# forty-third session: mask-s43 (mask-s36 trained 1000 steps more on sk-mask-mix2: sk-mask-mix
# and 320 new recordings of seed 4) scored on validation against the shipped default (-s41):
# frame by frame behind pose-s35 on sk-src's 56 dancers, presence and depth scale refitted on
# sk-mask-mix's 104 validation recordings, then as deployed on the 56 dancers (with the mask
# IoU as deployed, new). The default's own files: net56-default-s42, run56-default-s43.
set -eu
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s41.json
$Y weights combine --mask $D/runs/mask-s43/final.h5 --pose models/campaign/pose-s35/checkpoint.h5 --config $CFG \
  -o $D/runs/mask-s43-s43.h5
$Y eval --weights $D/runs/mask-s43-s43.h5 --data $D/sk-src/val --seconds 2.5 --threads 2 --json $R/net56-mask-s43-s43.json \
  > $R/net56-mask-s43-s43.txt 2>&1
/usr/bin/python3 benchmarks/training/paired.py $R/net56-default-s42.json $R/net56-mask-s43-s43.json
$Y weights calibrate --weights $D/runs/mask-s43-s43.h5 --data $D/sk-mask-mix/val --seconds 2 --beta 0.94 --presence-tau 0.5 \
  --depth-tau 0.5 --depth-without-forearms --threads 2 -o $D/runs/mask-s43-s43-cal.h5 > $R/calibrate-mask-s43-maskmix-s43.txt 2>&1
$Y eval --weights $D/runs/mask-s43-s43-cal.h5 --data $D/sk-src/val --run --seconds 2.5 --threads 2 \
  --poses $D/runs/mask-s43-s43-run56.csv --json $R/run56-mask-s43-s43.json > $R/run56-mask-s43-s43.txt 2>&1
/usr/bin/python3 benchmarks/training/paired.py --poses --root --common $D/runs/default-s43-run56.csv $D/runs/mask-s43-s43-run56.csv
