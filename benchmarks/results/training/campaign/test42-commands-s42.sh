#!/bin/bash
# forty-second session: the test draws prepared for a candidate (here -s41's networks with
# run.mask_mirror, refitted: mirror-s42-cal.h5) against the shipped default (-s41), to be read
# once after a choice on validation. NOT RUN: the candidate was not chosen (too slow), so the
# seeds stay unread for the next one: 20261226 (test split, made: $D/test-s42), 20261227 (--sim test).
set -u
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
[ -f $D/test-s42/manifest.json ] || $Y sim --dataset $D/test-s42 --seed 20261226 --train 0 --val 0 --test 16 --test-empty 16 \
  --test-rooms 16 --test-dancer-rooms 8 --duration 3s --random-looks --frame-dancer --threads 2
for w in mirror default; do
  W=$D/runs/mirror-s42-cal.h5; [ $w = default ] && W=models/default.h5
  date; echo "== $w run test-s42"
  $Y eval --run --weights $W --data $D/test-s42/test --seconds 2.5 --skip 0.5 --threads 2 --poses $D/runs/$w-test42.csv --json $R/test42-$w-run-s42.json > $R/test42-$w-run-s42.txt 2>&1
  date; echo "== $w eval test-s42"
  $Y eval --weights $W --data $D/test-s42/test --seconds 2.5 --skip 0.5 --threads 2 --json $R/test42-$w-s42.json > $R/test42-$w-s42.txt 2>&1
  date; echo "== $w eval sim test 20261227"
  $Y eval --weights $W --sim test --seed 20261227 --scenes 48 --threads 2 --json $R/test42sim-$w-s42.json > $R/test42sim-$w-s42.txt 2>&1
done
date; echo done
