#!/usr/bin/env bash
# bench_alternating.sh OLD.h5 NEW.h5 OUT.txt [NOTE]: `yelan bench run --threads-list 1` on two
# weights files in alternating rounds (ROUNDS, default 9; SERIES=b: the old file's rounds
# first), the kernel peak measured before and after, the per-round ratios and medians by
# alternating_rounds.py. Machines are shared and noisy: nothing else may run beside it.
# Y_OLD=BINARY: the old rounds run that build of yelan (two builds on the same weights).
# ARGS: more flags for both sides' bench run (e.g. ARGS='--mask-max-age 2'); OLD_ARGS: for the
# old side's alone (OLD_ARGS='--bf16 off': one build, one file, stage 1 in fp32 against bf16);
# NEW_ARGS: for the new side's alone (NEW_ARGS='--mask-max-age 2': another run setting against the old's).
set -euo pipefail
cd "$(dirname "$0")/../.."
old=$1 new=$2 out=$3 note=${4:-}
D=${D:-/var/tmp/yelan-data} Y=${Y:-build/release/yelan}
raw=$D/bench-alternating-$$.raw
rm -f "$raw"
order="new old"
[ -n "${SERIES:-}" ] && order="old new"
{
  echo "# $(date -u +%F): yelan bench run --weights W --threads-list 1 --no-torch${ARGS:+ $ARGS}${OLD_ARGS:+ (old side also $OLD_ARGS)}${NEW_ARGS:+ (new side also $NEW_ARGS)}, alternating rounds ($order)"
  echo "# CPU: $(lscpu | grep 'Model name' | sed 's/  */ /g')"
  echo "# peak: $("$Y" bench kernels --quick 2>&1 | grep -i '^peak' | head -1)"
  echo "# old: $old${Y_OLD:+ (by $Y_OLD)}; new: $new${Y_OLD:+ (by $Y)}${note:+; $note}; nothing else running"
} > "$out"
for r in $(seq 1 "${ROUNDS:-9}"); do
  for w in $order; do
    W=$old Yw=${Y_OLD:-$Y} side_args=${OLD_ARGS:-}
    [ "$w" = new ] && W=$new Yw=$Y side_args=${NEW_ARGS:-}
    log=$D/bench-alternating-$$-$w-$r.txt
    # shellcheck disable=SC2086  # ARGS is a list of flags
    "$Yw" bench run --weights "$W" --threads-list 1 --no-torch ${ARGS:-} $side_args > "$log" 2>&1
    echo "$w $r $(awk '$2=="1" && $3+0>0 {print $3; exit}' "$log")" | tee -a "$raw"
  done
done
/usr/bin/python3 benchmarks/training/alternating_rounds.py "$raw" >> "$out"
echo "# peak after the rounds: $("$Y" bench kernels --quick 2>&1 | grep -i '^peak' | head -1)" >> "$out"
cat "$out"
