#!/bin/bash
# forty-first session: yelan bench run at one thread, alternating the previous default and the new one
set -u
cd /work/main
D=/var/tmp/yelan-data; Y=$D/yelan-s40; R=benchmarks/results/training/campaign
out=$R/bench-run-s41.txt
peak=$($Y bench kernels --quick 2>&1 | grep -i "^peak" | head -1)
{
echo "# Session 2026-12-03 (forty-first): yelan bench run --weights W --threads-list 1 --no-torch"
echo "# CPU: $(lscpu | grep 'Model name' | sed 's/  */ /g')"
echo "# peak: $peak"
echo "# old: the default of 3d9f255~1 (-s37: mask-s32 + pose-s35); new: mask-s36 + pose-s35 (-s41); alternating rounds new, old (a second series, new first); nothing else running"
} > $out
for r in $(seq 1 15); do
  for w in new old; do
    W=$D/runs/default-s37.h5; [ $w = new ] && W=models/default.h5
    $Y bench run --weights $W --threads-list 1 --no-torch > $D/bench-$w-$r.txt 2>&1
    v=$(awk '$2=="1" && $3+0>0 {print $3; exit}' $D/bench-$w-$r.txt)
    echo "$w $r $v" | tee -a $D/bench-s41.raw
  done
done
/usr/bin/python3 benchmarks/training/alternating_rounds.py $D/bench-s41.raw >> $out
echo "# peak after the rounds: $($Y bench kernels --quick 2>&1 | grep -i "^peak" | head -1)" >> $out
cat $out
