#!/usr/bin/env bash
# bench-vetting.sh DATASET OLD_YELAN [NEW_YELAN]: what vetting a dataset's recordings costs a
# new machine (camera/io/untrusted.h). A one-step mask training (batch 32, 48 validation
# windows, two threads) from an empty vetting cache, ROUNDS times each way (default 1):
#   OLD_YELAN (a build before 2026-11-29) vets each recording when the trainer first opens
#   it, forked from a process that already holds its networks;
#   NEW_YELAN (default build/release/yelan) vets every recording up front, one child per
#   thread, before the networks are allocated.
# Each run's files vetted are counted from its cache file. Run it alone on the machine.
set -euo pipefail
data=$1; old=$2; new=${3:-build/release/yelan}
cfg=${CFG:-benchmarks/configs/small-pose0.125.json}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
one() {  # one NAME BINARY: seconds, files vetted
  local t0 t1
  rm -f "$tmp/cache"; rm -rf "$tmp/run"
  t0=$(date +%s.%N)
  YELAN_VET_CACHE="$tmp/cache" "$2" train --stage mask --config "$cfg" --data "$data" -o "$tmp/run" --steps 1 --batch 32 \
    --mask-frames 1 --windows-per-visit 15 --val-windows 48 --threads 2 --quiet > "$tmp/$1.out" 2>&1
  t1=$(date +%s.%N)
  printf '%-4s %7.1f s  %4d files vetted  %s\n' "$1" "$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')" "$(wc -l < "$tmp/cache")" \
    "$(grep -h '^vetted' "$tmp/$1.out" || true)"
}
echo "# $(date -u +%FT%TZ) $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) CPUs; $data"
for _ in $(seq "${ROUNDS:-1}"); do one old "$old"; one new "$new"; done
