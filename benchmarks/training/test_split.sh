#!/usr/bin/env bash
# test_split.sh SEED NAME TAG=WEIGHTS...: a fresh test split (yelan sim --dataset $D/NAME, seed
# SEED: 16 dancers, 16 empty scenes, 16 furnished rooms with nobody, 8 dancers in furnished
# rooms, 3 s each; made once) scored as deployed (`yelan eval --run`) for each weights file,
# results in benchmarks/results/training/campaign/test-NAME-TAG.{txt,json}, poses in
# $D/runs/TAG-NAME.csv; the first two paired (root-aligned, common poses). A test split is read
# once, after the choice on validation: never choose with it. Environment: D, Y, THREADS (2).
set -euo pipefail
cd "$(dirname "$0")/../.."
seed=$1 name=$2
shift 2
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan} R=benchmarks/results/training/campaign
[ -f "$D/$name/manifest.json" ] || "$Y" sim --dataset "$D/$name" --seed "$seed" --train 0 --val 0 --test 16 --test-empty 16 \
  --test-rooms 16 --test-dancer-rooms 8 --duration 3s --random-looks --frame-dancer --threads "${THREADS:-2}"
csvs=()
for tw in "$@"; do
  tag=${tw%%=*} w=${tw#*=}
  echo "== $tag ($w) on $name, $(date -u +%FT%TZ)"
  "$Y" eval --run --weights "$w" --data "$D/$name/test" --seconds 2.5 --skip 0.5 --threads "${THREADS:-2}" \
    --poses "$D/runs/$tag-$name.csv" --json "$R/test-$name-$tag.json" > "$R/test-$name-$tag.txt" 2>&1
  grep -E "^deployed path|^presence|^mask IoU|poses of scenes with nobody" "$R/test-$name-$tag.txt" || true
  csvs+=("$D/runs/$tag-$name.csv")
done
[ ${#csvs[@]} -ge 2 ] && /usr/bin/python3 benchmarks/training/paired.py --poses --root --common "${csvs[0]}" "${csvs[1]}"
