#!/bin/bash
# forty-first session: the test draws for cand-s41 (mask-s36 + pose-s35) and default-s37, read once after the choice
set -u
cd /work/main
D=/var/tmp/yelan-data; Y=$D/yelan-s40; R=benchmarks/results/training/campaign
for w in cand default; do
  W=$D/runs/$w-s41.h5; [ $w = default ] && W=$D/runs/default-s37.h5
  date; echo "== $w run test-s41"
  $Y eval --run --weights $W --data $D/test-s41/test --seconds 2.5 --skip 0.5 --threads 2 --poses $D/runs/$w-test41.csv --json $R/test41-$w-run-s41.json > $R/test41-$w-run-s41.txt 2>&1
  date; echo "== $w eval test-s41"
  $Y eval --weights $W --data $D/test-s41/test --seconds 2.5 --skip 0.5 --threads 2 --json $R/test41-$w-s41.json > $R/test41-$w-s41.txt 2>&1
done
for w in cand default; do
  W=$D/runs/$w-s41.h5; [ $w = default ] && W=$D/runs/default-s37.h5
  date; echo "== $w eval sim test 20261225"
  $Y eval --weights $W --sim test --seed 20261225 --scenes 48 --threads 2 --json $R/test41sim-$w-s41.json > $R/test41sim-$w-s41.txt 2>&1
done
date; echo done
