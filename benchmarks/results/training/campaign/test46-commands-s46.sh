#!/bin/bash
# forty-sixth session: issue 15's own command on the shipped default (-s44: mask-s43 + pose-s35),
# --sim test seed 20261227 (drawn by no session before, read once; nothing chosen with it)
set -u
cd "$(dirname "$0")/../../../.."
Y=build/release/yelan R=benchmarks/results/training/campaign
date; echo "== default eval sim test 20261227"
$Y eval --weights models/default.h5 --sim test --seed 20261227 --scenes 48 --threads 2 --json $R/test46sim-default-s46.json > $R/test46sim-default-s46.txt 2>&1
date; echo done
