#!/usr/bin/env bash
# bench_read_threads.sh DATA VAL OUT.txt: the trainer's speed with a batch's windows read one
# after another (--read-threads 1, "old") against two at a time (2, "new"), in alternating
# rounds (ROUNDS, default 5) of STEPS (default 40) training steps each: stage 2 by ev-fp2's
# recipe (the s16 config, true masks, batch 8) from sk-sided's stick net on DATA's
# recordings, two threads. Y_OLD / Y_NEW (default both Y) and R_OLD / R_NEW (default 1 / 2)
# set each side's binary and --read-threads, so the same rounds also compare two builds. A
# round's figure is steps a minute over its steps 3..STEPS by the log's wall clock (the
# cursors' first files opened and the closing validation left out).
# Machines are shared and noisy: nothing else may run beside it.
set -euo pipefail
cd "$(dirname "$0")/../.."
data=$1 val=$2 out=$3
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan}
y_old=${Y_OLD:-$Y} y_new=${Y_NEW:-$Y} r_old=${R_OLD:-1} r_new=${R_NEW:-2}
steps=${STEPS:-40}
cfg=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16.json
work=$D/bench-read-threads-$$
raw=$work.raw
rm -rf "$work" "$raw"
mkdir -p "$work"
{
  echo "# $(date -u +%F): yelan train (pose, $cfg, batch 8, two threads): old $y_old --read-threads $r_old against new $y_new --read-threads $r_new, $steps steps a round, alternating rounds; figures: steps a minute"
  echo "# CPU: $(lscpu | sed -n 's/^Model name: *//p'), family $(lscpu | sed -n 's/^CPU family: *//p') model $(lscpu | sed -n 's/^Model: *//p'), $(grep -o -w 'avx2\|avx512f\|amx_tile' /proc/cpuinfo | sort -u | tr '\n' ' ')"
  echo "# data: $data; nothing else running"
} > "$out"
for r in $(seq 1 "${ROUNDS:-5}"); do
  for side in new old; do
    R=$r_new y=$y_new
    [ "$side" = old ] && R=$r_old y=$y_old
    run=$work/$side-$r
    "$y" train --stage pose --config "$cfg" --data "$data" --val-data "$val" -o "$run" --steps "$steps" --batch 8 \
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
cat "$out"
