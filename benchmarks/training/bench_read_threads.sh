#!/usr/bin/env bash
# bench_read_threads.sh DATA VAL OUT.txt: the trainer's speed with a batch's windows read one
# after another (--read-threads 1, "old") against two at a time (2, "new"), in alternating
# rounds (ROUNDS, default 5) of STEPS (default 40) training steps each: stage 2 by ev-fp2's
# recipe (the s16 config, true masks, batch 8) from sk-sided's stick net on DATA's
# recordings, two threads. A round's figure is steps a minute over its steps 3..STEPS by the
# log's wall clock (the cursors' first files opened and the closing validation left out).
# Machines are shared and noisy: nothing else may run beside it.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=$1 val=$2 out=$3
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan}
steps=${STEPS:-40}
cfg=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16.json
work=$D/bench-read-threads-$$
raw=$work.raw
rm -rf "$work" "$raw"
mkdir -p "$work"
{
  echo "# $(date -u +%F): yelan train (pose, $cfg, batch 8, two threads) --read-threads 1 (old) against 2 (new), $steps steps a round, alternating rounds; figures: steps a minute"
  echo "# CPU: $(lscpu | grep 'Model name' | sed 's/  */ /g')"
  echo "# data: $data; nothing else running"
} > "$out"
for r in $(seq 1 "${ROUNDS:-5}"); do
  for side in new old; do
    R=2
    [ "$side" = old ] && R=1
    run=$work/$side-$r
    "$Y" train --stage pose --config "$cfg" --data "$data" --val-data "$val" -o "$run" --steps "$steps" --batch 8 \
      --epoch-steps "$steps" --val-windows 4 --lr 1e-3 --seed 18 --init models/campaign/sk-sided/checkpoint.h5 \
      --threads 2 --read-threads "$R" --quiet > "$run.out" 2>&1
    # log.csv: step, epoch, loss, validation, lr, grad norm, samples/s, wall s, ...
    awk -F, -v side="$side" -v r="$r" -v n="$steps" 'NR > 1 && $1 == 2 { w0 = $8 } NR > 1 && $1 == n { w1 = $8 }
      END { printf "%s %d %.3f\n", side, r, 60 * (n - 2) / (w1 - w0) }' "$run/log.csv" >> "$raw"
    grep -o 'data [0-9]*% of step time' "$run.out" | sed "s/^/# $side round $r: /" >> "$out"
  done
done
benchmarks/training/alternating_rounds.py "$raw" >> "$out"
rm -rf "$work" "$raw"
mkdir -p "$work"
cat "$out"
