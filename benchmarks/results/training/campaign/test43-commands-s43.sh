#!/bin/bash
# forty-third session: the test split of seed 20261226 ($D/test-s42, made by the forty-second
# session, unread until now) as deployed, for the age-6 candidate (age6-s43-cal.h5: the
# shipped networks with run.mask_max_age 6, refitted) and the shipped default (-s41). Frame by
# frame both are the same networks: eval --run is where they differ.
set -u
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
[ -f $D/test-s42/manifest.json ] || $Y sim --dataset $D/test-s42 --seed 20261226 --train 0 --val 0 --test 16 --test-empty 16 \
  --test-rooms 16 --test-dancer-rooms 8 --duration 3s --random-looks --frame-dancer --threads 2
for w in age6 default; do
  W=$D/runs/age6-s43-cal.h5; [ $w = default ] && W=models/default.h5
  date; echo "== $w run test-s42"
  $Y eval --run --weights $W --data $D/test-s42/test --seconds 2.5 --skip 0.5 --threads ${THREADS:-2} --poses $D/runs/$w-test43.csv \
    --json $R/test43-$w-run-s43.json > $R/test43-$w-run-s43.txt 2>&1
done
/usr/bin/python3 benchmarks/training/paired.py --poses --root --common $D/runs/default-test43.csv $D/runs/age6-test43.csv
date; echo done
