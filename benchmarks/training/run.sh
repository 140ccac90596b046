#!/usr/bin/env bash
# Retrains and re-evaluates every model of benchmarks/README.md's comparison table and
# frontier chart (issue 7), two trainings at a time on one thread each:
#   benchmarks/training/run.sh [OUT_DIR=runs/training] [WHICH=all|a|b|...]
# Needs build/release/yelan and the mask net of models/small-first.h5 (the shared stage 1).
# Then: benchmarks/training/report.py OUT_DIR  (table, JSON, frontier chart).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-runs/training}
which=${2:-all}
yelan=${YELAN:-build/release/yelan}
mask=${MASK:-models/small-first.h5}
mkdir -p "$out"

# id config budget [extra flags]; budget "steps" = 2500 steps (the comparison), "minutes" =
# 2500 steps or 30 CPU-minutes, whichever comes first (the size sweep: the widest net gets
# fewer steps; CPU time, so other work on the machine does not eat the budget).
jobs=(
  "a benchmarks/configs/small-frames-plain.json steps"
  "b benchmarks/configs/small-tore-plain.json steps"
  "c small steps"
  "d benchmarks/configs/small-nomask.json steps"
  "e benchmarks/configs/small-noconvlstm.json steps"
  "f small steps --occlusion"
  "p0125 benchmarks/configs/small-pose0.125.json minutes"
  "p05 benchmarks/configs/small-pose0.5.json minutes"
)

train_and_eval() {
  local id=$1 config=$2 budget=$3; shift 3
  local dir=$out/$id limit
  if [ "$budget" = steps ]; then limit="--steps 2500 --max-minutes 90"; else limit="--steps 2500 --max-cpu-minutes 30"; fi
  # shellcheck disable=SC2086
  "$yelan" train --stage pose --config "$config" --sim train -o "$dir" $limit --epoch-steps 250 --val-windows 8 \
      --checkpoint-minutes 5 --threads 1 --quiet "$@" > "$dir.train.txt" 2>&1
  if grep -q '"masked_input": *false' "$config" 2>/dev/null; then
    cp "$dir/best.h5" "$dir/model.h5"  # no stage 1: the pose file is the whole model
  else
    "$yelan" weights combine --mask "$mask" --pose "$dir/best.h5" -o "$dir/model.h5" > /dev/null
  fi
  "$yelan" eval --weights "$dir/model.h5" --sim test --seed 1 --scenes 48 --seconds 1 --threads 1 \
      --json "$out/eval-$id.json" > "$out/eval-$id.txt" 2>&1
}

running=0
for j in "${jobs[@]}"; do
  # shellcheck disable=SC2086
  set -- $j
  if [ "$which" != all ] && [ "$which" != "$1" ]; then continue; fi
  train_and_eval "$@" &
  running=$((running + 1))
  if [ $running -ge 2 ]; then wait -n; running=$((running - 1)); fi
done
wait
