#!/bin/bash
# forty-third session: yelan bench run at one thread, alternating the shipped default (-s41)
# and the candidate with early exit capped by age (run.mask_max_age 6, refitted: age6-s43-cal.h5).
# SERIES=b: a second series, the old file's rounds first. Nothing else running.
set -u
cd /work/main
D=/var/tmp/yelan-data; Y=${Y:-build/release/yelan}; R=benchmarks/results/training/campaign
tag=${TAG:-age6}
series=${SERIES:-}
out=$R/bench-run-$tag$series-s43.txt raw=$D/bench-$tag$series-s43.raw
rm -f $raw
peak=$($Y bench kernels --quick 2>&1 | grep -i "^peak" | head -1)
{
echo "# Session 2026-12-04 (forty-third): yelan bench run --weights W --threads-list 1 --no-torch"
echo "# CPU: $(lscpu | grep 'Model name' | sed 's/  */ /g')"
echo "# peak: $peak"
echo "# old: models/default.h5 of 5aa278d (-s41: mask-s36 + pose-s35); new: the same networks with run.mask_max_age 6 ($tag), presence and depth refitted; alternating rounds $([ -n "$series" ] && echo old, new || echo new, old); nothing else running"
} > $out
for r in $(seq 1 ${ROUNDS:-9}); do
  for w in $([ -n "$series" ] && echo old new || echo new old); do
    W=models/default.h5; [ $w = new ] && W=$D/runs/$tag-s43-cal.h5
    $Y bench run --weights $W --threads-list 1 --no-torch > $D/bench43-$tag$series-$w-$r.txt 2>&1
    v=$(awk '$2=="1" && $3+0>0 {print $3; exit}' $D/bench43-$tag$series-$w-$r.txt)
    echo "$w $r $v" | tee -a $raw
  done
done
/usr/bin/python3 benchmarks/training/alternating_rounds.py $raw >> $out
echo "# peak after the rounds: $($Y bench kernels --quick 2>&1 | grep -i "^peak" | head -1)" >> $out
cat $out
