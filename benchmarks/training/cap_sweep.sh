#!/usr/bin/env bash
# cap_sweep.sh TAG W [CAPS]: one weights file run as deployed on sk-src's 56 validation dancers
# once per early-exit age cap (CAPS, default "1 2 3 6"; 1 runs stage 1 on every tick), the
# JSONs in OUT (default benchmarks/results/training/campaign) as run56-TAG-capK.json and the
# poses in $D/runs/TAG-capK-run56.csv (for paired.py --poses). Chart two files' sweeps with
#   early_exit_frontier.py --svg OUT.svg A=1:A-cap1.json,2:A-cap2.json,... B=...
# The data: campaign.sh val-data. Environment: D, Y, THREADS (default 2), OUT.
set -euo pipefail
cd "$(dirname "$0")/../.."
tag=$1 w=$2
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan} out=${OUT:-benchmarks/results/training/campaign}
mkdir -p "$out" "$D/runs"
for k in ${3:-1 2 3 6}; do
  "$Y" eval --weights "$w" --data "$D/sk-src/val" --run --seconds 2.5 --threads "${THREADS:-2}" --mask-max-age "$k" \
    --poses "$D/runs/$tag-cap$k-run56.csv" --json "$out/run56-$tag-cap$k.json" > "$out/run56-$tag-cap$k.txt" 2>&1
  echo "cap $k: $(grep -m1 '^mask IoU as deployed' "$out/run56-$tag-cap$k.txt" | cut -c1-150 || true)"
done
