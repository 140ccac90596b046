#!/bin/bash
# forty-second session: stage 1 mirror-averaged (run.mask_mirror) scored on validation against
# the shipped default (-s41): frame by frame on sk-src's 56 dancers, presence refitted on
# sk-mask-mix's 104 validation recordings, then as deployed on the 56 dancers. TAG=mirror
# (run.mask_mirror true) or TAG=doubt (0.05: only where presence is in doubt).
set -eu
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
tag=${TAG:-mirror}
$Y weights combine --mask models/campaign/mask-s36/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
  --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s42-$tag.json -o $D/runs/$tag-s42.h5
if [ $tag = mirror ]; then
  for w in $D/runs/mirror-s42.h5 models/default.h5; do
    n=mirror; [ $w = models/default.h5 ] && n=default
    $Y eval --weights $w --data $D/sk-src/val --seconds 2.5 --threads 2 --json $R/net56-$n-s42.json > $R/net56-$n-s42.txt 2>&1
  done
  /usr/bin/python3 benchmarks/training/paired.py $R/net56-default-s42.json $R/net56-mirror-s42.json
fi
$Y weights calibrate --weights $D/runs/$tag-s42.h5 --data $D/sk-mask-mix/val --seconds 2 --beta 0.94 --presence-tau 0.5 \
  --depth-tau 0.5 --depth-without-forearms --threads 2 -o $D/runs/$tag-s42-cal.h5 > $R/calibrate-$tag-s42-maskmix-s42.txt 2>&1
$Y eval --weights $D/runs/$tag-s42-cal.h5 --data $D/sk-src/val --run --seconds 2.5 --threads 2 --poses $D/runs/$tag-s42-run56.csv \
  --json $R/run56-$tag-s42.json > $R/run56-$tag-s42.txt 2>&1
# the default's poses on the same ticks: models/default.h5 as the forty-first session ran it (run56-cand-s41)
/usr/bin/python3 benchmarks/training/paired.py --poses --root --common $D/runs/cand-s41-run56.csv $D/runs/$tag-s42-run56.csv
