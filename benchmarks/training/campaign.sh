#!/usr/bin/env bash
# The recipe of the shipped model (issue 15), rerunnable on a 2-core machine: one dataset made
# once, the mask net and the pose net trained side by side at one thread each (never two
# thread pools on two cores), then combined. Every step resumes: the dataset keeps its done
# files, and a training with a checkpoint continues bit-exactly (--resume), so the campaign
# may be stopped and restarted over days. Logs and checkpoints go to $RUNS.
#   benchmarks/training/campaign.sh [TARGET]   (`campaign.sh help` lists the targets: the case
#   labels below, read from this file so the list cannot go stale; default: all)
# Environment: Y (the yelan binary), DATA (dataset folder), RUNS (runs folder), CFG (config),
# POSE_STEPS / MASK_STEPS (the runs' lengths: the cosine schedules' horizons).
# THREADS (default 1: two runs side by side; 2 for one run alone, bit-exact either way).
set -euo pipefail
cd "$(dirname "$0")/../.."
Y=${Y:-build/release/yelan}
DATA=${DATA:-/var/tmp/yelan-data/ds-s1}
# The same draw with a new person in every training recording (--random-looks) and every
# dancer framed (--frame-dancer: in ds-s1 a quarter of the joints are out of the picture,
# and 7 of the 32 val recordings never show their dancer); the empty scenes are ds-s1's
# files (hard links, or simulated again: the same events).
DATA_LOOKS=${DATA_LOOKS:-/var/tmp/yelan-data/ds-s2}
# ds-s2 with low light at 20 DN, the simulator's since 2026-11-27 (ds-s2's low-light dancers
# hardly show in the events): only its low-light members differ.
DATA_S3=${DATA_S3:-/var/tmp/yelan-data/ds-s3}
DATA_S4=${DATA_S4:-/var/tmp/yelan-data/ds-s4}
DATA_S5=${DATA_S5:-/var/tmp/yelan-data/ds-s5}
RUNS=${RUNS:-/var/tmp/yelan-data/runs}
CFG=${CFG:-benchmarks/configs/small-pose0.125.json}
POSE_STEPS=${POSE_STEPS:-14000}
MASK_STEPS=${MASK_STEPS:-4000}
what=${1:-all}

# The default shipped from 2026-11-30 to 2026-12-02 (stage 1 mask-s16, stage 2 pose-s21-reuse;
# commit 5edf698): the runs of the twenty-fifth to thirty-fifth sessions start from it or run
# behind its stage 1. models/default.h5 is another model since; this is that file, from git.
default_s25() {
  local f=$RUNS/default-5edf698.h5
  if [ ! -f "$f" ]; then
    mkdir -p "$RUNS"
    git show 5edf698:models/default.h5 > "$f.tmp" && mv "$f.tmp" "$f"
  fi
  echo "$f"
}

# Both datasets were drawn before low light was raised from 4 to 20 DN (--low-light-dn 4
# makes the same files; at 4 DN a low-light dancer hardly shows in the events).
dataset_looks() {
  mkdir -p "$DATA_LOOKS/train" "$DATA_LOOKS/val"
  if [ -d "$DATA/val" ]; then
    ln -f "$DATA"/val/val-empty-*.yelan.h5 "$DATA_LOOKS/val/" 2>/dev/null || true
    ln -f "$DATA"/train/train-empty-*.yelan.h5 "$DATA_LOOKS/train/" 2>/dev/null || true
  fi
  "$Y" sim --dataset "$DATA_LOOKS" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 48 --val-empty 8 --duration 5s \
    --random-looks --frame-dancer --low-light-dn 4 --threads 2
}

# The other members are the same bytes as ds-s2's (hard links); only the low-light ones
# (69 of 288) are simulated, about 16 min on 2 cores (all of them without ds-s2).
dataset_s3() {
  mkdir -p "$DATA_S3/train" "$DATA_S3/val"
  for split in train val; do
    [ -d "$DATA_LOOKS/$split" ] || continue
    for f in "$DATA_LOOKS/$split"/*.yelan.h5; do
      case "$(basename "$f")" in *-low-*) ;; *) ln -f "$f" "$DATA_S3/$split/" ;; esac
    done
  done
  "$Y" sim --dataset "$DATA_S3" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 48 --val-empty 8 --duration 5s \
    --random-looks --frame-dancer --threads 2
}

# link_splits FROM TO: FROM's train and val recordings hard-linked into TO, a dataset grown
# from FROM (the same seed gives the same files, so nothing is simulated twice).
link_splits() {
  mkdir -p "$2/train" "$2/val"
  for split in train val; do
    [ -d "$1/$split" ] || continue
    ln -f "$1/$split"/*.yelan.h5 "$2/$split/"
  done
}

# ds-s3 and furnished rooms with nobody in them (most filmed by a hand-held camera looking
# around): ds-s3's empty scenes are bare walls, and on the real DAVIS346 file (a furnished
# room, a moving camera) stage 1 still sees a person. Only the rooms are simulated.
dataset_s4() {
  link_splits "$DATA_S3" "$DATA_S4"
  "$Y" sim --dataset "$DATA_S4" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 48 --val-empty 8 --duration 5s \
    --random-looks --frame-dancer --train-rooms "${ROOMS_TRAIN:-32}" --val-rooms "${ROOMS_VAL:-8}" --threads "${THREADS:-2}"
}

# Made from nothing (no ds-s4 beside it) it simulates all 400 members: 1.29 CPU-h on
# 2026-11-28 with the simulator's faster flicker (whose members differ from the first ds-s5's).
# ds-s4 with twice the furnished rooms and dancers in furnished rooms (their camera still,
# panning, shaking or sweeping): stage 1 said "person" on 16% of ds-s4's validation room
# ticks, most of them low-light rooms whose walkers and furniture it took for a dancer, and
# it had never had to find a dancer among furniture. Only the new members are simulated.
dataset_s5() {
  link_splits "$DATA_S4" "$DATA_S5"
  "$Y" sim --dataset "$DATA_S5" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 48 --val-empty 8 --duration 5s \
    --random-looks --frame-dancer --train-rooms 64 --val-rooms 16 --train-dancer-rooms 24 --val-dancer-rooms 8 \
    --threads "${THREADS:-2}"
}

# ds-s5 with three times the scenes with nobody in validation (24 empty scenes, 48 furnished
# rooms) and twice in training (96, 128): on the test split of seed 20261208 the shipped stage 1
# called "person" on 8 of 32 scenes with nobody, mostly high light with a moving background,
# a kind validation's 24 such scenes never showed; a split that selects for issue 16's 2%
# needs more of them. Only the new members are simulated (about 40 CPU-min).
DATA_S6=${DATA_S6:-/var/tmp/yelan-data/ds-s6}
# dataset_rooms FROM TO TRAIN_DANCER_ROOMS VAL_DANCER_ROOMS: ds-s6's draw grown from FROM's
# files (hard links) with this many dancers in furnished rooms.
dataset_rooms() {
  link_splits "$1" "$2"
  "$Y" sim --dataset "$2" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 96 --val-empty 24 --duration 5s \
    --random-looks --frame-dancer --train-rooms 128 --val-rooms 48 --train-dancer-rooms "$3" --val-dancer-rooms "$4" \
    --threads "${THREADS:-2}"
}
dataset_s6() { dataset_rooms "$DATA_S5" "$DATA_S6" 24 8; }

# ds-s6 with five times the training dancers in furnished rooms (120, 96 new) and three times
# in validation (24): ds-s6 trains on 15 dancers filmed by a moving camera (sweep, pan) against
# 115 empty rooms filmed so, and on its validation's 4 such dancers stage 1 scores IoU
# 0.22 (mask-s10) to 0.39 (mask-s15) where the other 36 dancers score 0.74 (2026-11-29,
# fifteenth session). Only the new members are simulated.
DATA_S7=${DATA_S7:-/var/tmp/yelan-data/ds-s7}
dataset_s7() { dataset_rooms "$DATA_S6" "$DATA_S7" 120 24; }

# ds-s7 and remixed arms (2026-11-29, seventeenth session): on ds-s7's validation the pose net
# is 24% under the per-view floor on procedural dances and at the floor on the CMU clips' held-
# out stretches (hands and elbows are most of the error): 13 clips hold few arm-and-body poses.
# Half the training dancers (plain and in rooms) are drawn again with each arm playing its
# clip 0.25-3 s after the body (named ...-remix); ds-s7's files stay beside them (hard
# links), so ds-s8 trains on both. Only the remixed members are simulated (about 160).
DATA_S8=${DATA_S8:-/var/tmp/yelan-data/ds-s8}
# dataset_arms DIR FLAGS...: ds-s7's files linked into DIR, and its members drawn again with FLAGS.
dataset_arms() {
  link_splits "$DATA_S7" "$1"
  "$Y" sim --dataset "$1" --seed 1 --train "${LOOKS_TRAIN:-200}" --val 32 --test 0 --train-empty 96 --val-empty 24 --duration 5s \
    --random-looks --frame-dancer --train-rooms 128 --val-rooms 48 --train-dancer-rooms 120 --val-dancer-rooms 24 \
    "${@:2}" --threads "${THREADS:-2}"
}
dataset_s8() { dataset_arms "$DATA_S8" --remix-arms 0.5; }

# ds-s7 and free arms (2026-11-30, twenty-fourth session): remixed arms (ds-s8) recombine the
# 13 clips' arm poses and moved nothing on their held-out stretches; here half the training
# dancers (plain and in rooms) are drawn again with both arms moving through key poses drawn
# anywhere in an arm's range on the clip's body (named ...-free; camera/sim/free_arms.h), arm
# poses no clip has. ds-s7's files stay beside them (hard links). 162 simulated, 951 s at two threads.
DATA_S9=${DATA_S9:-/var/tmp/yelan-data/ds-s9}
DATA_STICK=${DATA_STICK:-/var/tmp/yelan-data/stick}
DATA_SK_SRC=${DATA_SK_SRC:-/var/tmp/yelan-data/sk-src}
DATA_SK=${DATA_SK:-/var/tmp/yelan-data/sk}
DATA_SKS=${DATA_SKS:-/var/tmp/yelan-data/sks}
DATA_SK_FP2=${DATA_SK_FP2:-/var/tmp/yelan-data/sk-src-fp2}
DATA_FPR=${DATA_FPR:-/var/tmp/yelan-data/sk-fpr}
DATA_FPR_MIX=${DATA_FPR_MIX:-/var/tmp/yelan-data/sk-fpr-mix}
DATA_NEG=${DATA_NEG:-/var/tmp/yelan-data/sk-neg}
DATA_MASK_MIX=${DATA_MASK_MIX:-/var/tmp/yelan-data/sk-mask-mix}
DATA_S43=${DATA_S43:-/var/tmp/yelan-data/sk-s43}
DATA_MASK_MIX2=${DATA_MASK_MIX2:-/var/tmp/yelan-data/sk-mask-mix2}
DATA_S45=${DATA_S45:-/var/tmp/yelan-data/sk-s45}
DATA_MASK_MIX3=${DATA_MASK_MIX3:-/var/tmp/yelan-data/sk-mask-mix3}
DATA_MASK_MIX4=${DATA_MASK_MIX4:-/var/tmp/yelan-data/sk-mask-mix4}
DATA_S56=${DATA_S56:-/var/tmp/yelan-data/sk-s56}
# The shipped config with stage 1 at width 0.25 (sixtieth session; yelan weights narrow's target).
NARROW_CFG=${NARROW_CFG:-benchmarks/results/training/campaign/s60/config-mask0.25-s58.json}
STICK_CFG0=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16.json
dataset_s9() { dataset_arms "$DATA_S9" --free-arms 0.5; }

dataset() {
  "$Y" sim --dataset "$DATA" --seed 1 --train 320 --val 32 --test 0 --train-empty 48 --val-empty 8 --duration 5s \
    --low-light-dn 4 --threads 2
}

# train STAGE NAME STEPS [extra flags]: resumes when NAME has a checkpoint.
train() {
  local stage=$1 name=$2 steps=$3
  shift 3
  local resume=()
  [ -f "$RUNS/$name/checkpoint.state" ] && resume=(--resume)
  "$Y" train --stage "$stage" --config "$CFG" --data "$DATA" -o "$RUNS/$name" --steps "$steps" --batch "${BATCH:-8}" \
    --epoch-steps "${EPOCH_STEPS:-250}" --val-windows 48 --patience 1000 --checkpoint-minutes 5 --threads "${THREADS:-1}" --quiet "${resume[@]}" "$@" \
    > "$RUNS/$name.out" 2>&1
}

# mask_recipe NAME DIR STEPS SEED INIT [FLAGS]: stage 1's fine-tune since mask-s43 (batch 32, one mask
# frame, 15 windows a visit, mirrored, lr 1e-4 cosine) on DIR from INIT, windows drawn by SEED,
# validated on sk-mask-mix's validation. MASK_CFG: the training config (default stage 1 at 0.375);
# MASK_LR: the peak rate (default 1e-4).
mask_recipe() {
  local name=$1 data=$2 steps=$3 seed=$4 init=$5
  shift 5
  CFG=${MASK_CFG:-benchmarks/configs/small-mask0.375-pose0.125.json} DATA=$data BATCH=32 train mask "$name" "$steps" \
    --val-data "$DATA_MASK_MIX/val" --lr "${MASK_LR:-1e-4}" --mask-frames 1 --windows-per-visit 15 --flip --seed "$seed" --init "$init" "$@"
}

# masked_pose NAME STEPS INIT [flags]: stage 2 behind stage 1's masks (the true ones, or with
# --mask-weights the frozen mask net's own) on ds-s7, fine-tuned from INIT.
masked_pose() {
  local name=$1 steps=$2 init=$3
  shift 3
  CFG=benchmarks/configs/small-mask0.375-pose0.125-masked.json DATA=$DATA_S7 train pose "$name" "$steps" \
    --occlusion --lr 3e-4 --init "$init" "$@"
}

# sk_run NAME DIR [flags]: the stick recipe of 2026-12-01 (twenty-seventh) on DIR/{train,val}:
# STICK_CFG (default the shipped stage 2's config) from a random init, lr 1e-3 cosine.
sk_run() {
  local name=$1 dir=$2
  shift 2
  CFG=${STICK_CFG:-$STICK_CFG0} DATA=$dir/train train pose "${SK_NAME:-$name}" "${STICK_STEPS:-1500}" \
    --val-data "$dir/val" --lr 1e-3 "$@"
}

# s56_dancers DIR Q: DIR gets links to the dancer recordings of sk-s56's first Q quarters (160
# plain and 64 in furnished rooms a quarter; not its empty scenes: their joints weigh nothing
# in stage 2's loss), or the command fails naming the data-s56 run that is missing.
s56_dancers() {
  local dir=$1 q=$2 f
  mkdir -p "$dir"
  for f in $(seq -f "$DATA_S56/train/train-%05g-*.yelan.h5" 0 $((160 * q - 1))) \
      $(seq -f "$DATA_S56/train/train-dancer-room-%05g-*.yelan.h5" 0 $((64 * q - 1))); do
    [ -f "$f" ] || { echo "sk-s56 lacks ${f##*/}: S56_QUARTERS='$(seq -s ' ' 1 "$q")' $0 data-s56" >&2; exit 1; }
    ln -sf "$f" "$dir/${f##*/}"
  done
}

# s56_pose NAME STEPS SEED Q [flags]: the shipped stage 2 fine-tuned behind the shipped stage 1's
# reused masks (as early exit reuses them, periods up to 16) on the dancers of sk-s56's first Q
# quarters, windows drawn by SEED, lr POSE_LR (default 3e-4) cosine, validated on sk-src-fp2's
# validation dancers.
s56_pose() {
  local name=$1 steps=$2 seed=$3 q=$4 dir
  shift 4
  dir=$RUNS/sk-s56-q$(seq -s '' 1 "$q")-dancers
  s56_dancers "$dir" "$q"
  CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s58.json DATA=$dir \
    train pose "$name" "$steps" --val-data "$DATA_SK_FP2/val" --lr "${POSE_LR:-3e-4}" --seed "$seed" \
    --init models/default.h5 --mask-weights models/default.h5 --mask-reuse 16 "$@"
}

# data_neg: sk-neg, stage 1's empty scenes and furnished rooms with nobody in them (seed 3),
# its training and validation splits (resumes).
data_neg() {
  "$Y" sim --dataset "$DATA_NEG" --seed 3 --train 0 --val 0 --test 0 --train-empty 64 --val-empty 24 \
    --train-rooms 64 --val-rooms 24 --duration 5s --threads "${THREADS:-2}"
}

mkdir -p "$RUNS"
# The targets: the case labels of the dispatch below.
targets() { sed -n 's/^  \([a-z0-9-]*\))\( .*\)\{0,1\}$/\1/p' "$0"; }

case "$what" in
  dataset) dataset ;;
  dataset-looks) dataset_looks ;;
  dataset-s3) dataset_s3 ;;
  dataset-s4) dataset_s4 ;;
  dataset-s5) dataset_s5 ;;
  dataset-s6) dataset_s6 ;;
  dataset-s7) dataset_s7 ;;
  dataset-s8) dataset_s8 ;;
  dataset-s9) dataset_s9 ;;
  train)
    "$0" train-mask-s2 &
    "$0" train-pose &
    wait ;;
  train-mask) train mask mask-p0125 "$MASK_STEPS" ;;
  # The pose run's history, to repeat it exactly: --steps 20000 with the default patience (10)
  # early-stopped at 4750; --resume --patience 1000 (campaign.sh's) went on, stopped at 10276
  # (--stop-at 10276 repeats that); then the horizon was shortened to 14000
  # (POSE_STEPS=14000) so the cosine anneals within the campaign's budget (the schedule is
  # a function of the step and the horizon alone: lr drops from 4.9e-4 to 1.8e-4 at 10276).
  train-pose) train pose pose-p0125 "$POSE_STEPS" --occlusion ;;
  # The second size: the pose net at width 0.25 (config small), for the size curve. The
  # 0.125 net scored 243 mm on its own training recordings (above the per-view floor of
  # 173 mm on the same frames): it underfits, so the next step is width, not data.
  train-pose-small) CFG=weights_tools/configs/small.json train pose pose-small "${POSE_SMALL_STEPS:-8000}" --occlusion ;;
  # The same width from scratch on ds-s2 (a new person in every training recording, every
  # dancer framed): the 1/8 width fine-tuned there scores 157 mm on 16 of its own training
  # recordings (per-view floor 200), so it still underfits; this run is the size curve's
  # second point on the data the default will train on.
  train-pose-small-looks) CFG=weights_tools/configs/small.json DATA=$DATA_LOOKS train pose pose-small-looks "${POSE_SMALL_STEPS:-8000}" --occlusion ;;
  # The 1/8-width net from pose-p0125's last checkpoint (13065 steps on ds-s1, where its
  # validation had been flat for 2000 steps) on the same motions and scenes with a new
  # person in every training recording: does the looks' variety lift the validation?
  # --init needs a whole weights file: the checkpoint's pose group beside the shipped mask net.
  train-pose-looks)
    init="$RUNS/pose-p0125-13065.h5"
    [ -f "$init" ] || "$Y" weights combine --mask models/default.h5 --pose "$RUNS/pose-p0125/checkpoint.h5" --config "$CFG" -o "$init"
    DATA=$DATA_LOOKS train pose pose-looks "${POSE_LOOKS_STEPS:-4000}" --occlusion --lr 3e-4 --init "$init" ;;
  # The same net, fine-tuned from pose-looks' best on the whole TORE (no mask): behind the
  # shipped mask net (IoU 0.42) pose-looks scores 398 mm against 228 behind true masks.
  train-pose-looks-nomask)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_LOOKS train pose pose-looks-nomask \
      "${POSE_NOMASK_STEPS:-1000}" --occlusion --lr 3e-4 --init "$RUNS/pose-looks/best.h5" ;;
  # The default's pose net (pose-looks-nomask's step 1000, whose validation was still falling:
  # 274, 272, 260, 244 mm at steps 250-1000) on, from the shipped models/default.h5 (its pose
  # group is that net), a new cosine over POSE_NOMASK2_STEPS. Run 2026-11-27 (init: commit
  # 4ada6c1's default): validation flat at 230-245 mm from step 1000; ds-s2 val 237.8 -> 221.1
  # mm at step 4000 (shipped), 1.14 CPU-h.
  train-pose-looks-nomask2)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_LOOKS train pose pose-looks-nomask2 \
      "${POSE_NOMASK2_STEPS:-4000}" --occlusion --lr 3e-4 --init "${NOMASK2_INIT:-models/default.h5}" ;;
  # The quarter width from scratch on ds-s2, reading the whole TORE: behind the shipped mask
  # net the 1/8 width scored 398 mm on the framed test, without a mask 314 (true masks 228),
  # and the quarter width behind true masks was the first net under the val floor (171 mm
  # against 192 at step 3500). Deployed under small-presence (stage 1 for presence only).
  # Its history: steps 0-1043 with an 8000-step horizon (--stop-at 1043 repeats them), then
  # the horizon shortened to 5000 (the default here now) so the cosine anneals within the
  # campaign's 20 CPU-hours (lr 9.7e-4 -> 9.1e-4 at the resume).
  train-pose-small-nomask)
    CFG=benchmarks/configs/small-nomask.json DATA=$DATA_LOOKS train pose pose-small-nomask "${POSE_SMALL_STEPS:-5000}" --occlusion ;;
  # The shipped pose net on ds-s3, where low-light dancers show: a short cosine from
  # models/default.h5 (its pose group), as pose-looks-nomask2 on ds-s2.
  train-pose-s3)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S3 train pose pose-s3 \
      "${POSE_S3_STEPS:-1000}" --occlusion --lr 3e-4 --init "${POSE_S3_INIT:-models/default.h5}" ;;
  # Heatmap resolution against width at equal multiply-adds: the 1/8 width on the full
  # sensor (33 x 44 heatmaps, 535 MFLOP a pose) beside pose-small-nomask (the quarter width
  # at half resolution, 17 x 22 heatmaps, 459 MFLOP), the same data, occlusion and cosine
  # horizon. Both earlier nets underfit their own training recordings (184 and 198 mm on 24
  # of them, per-view floor 202) with an image error of about one heatmap pixel (18-20
  # sensor px; a 17 x 22 map's pixel is 16).
  train-pose-full-nomask)
    CFG=benchmarks/configs/full-pose0.125-nomask.json DATA=$DATA_LOOKS train pose pose-full-nomask "${POSE_FULL_STEPS:-5000}" --occlusion ;;
  # Stage 1 again, from mask-p0125's best, with the panning and shaking empty scenes the
  # dataset gained (the DAVIS recording has a moving camera and nobody in it).
  train-mask-neg) train mask mask-neg "${MASK_NEG_STEPS:-3000}" --lr 5e-4 --init "$RUNS/mask-p0125/best.h5" ;;
  # Stage 1 on this dataset, warm-started from the issue-7 mask net (the shipped model of
  # commit 89f0f09, taken from git history), dancer and empty scenes, a short cosine
  # (MASK_S2_STEPS) that fits one session at one thread (~3.7 s a step).
  train-mask-s2)
    init="$RUNS/mask-init-89f0f09.h5"
    [ -f "$init" ] || git show 89f0f09:models/default.h5 > "$init"
    train mask mask-s2 "${MASK_S2_STEPS:-800}" --lr 5e-4 --init "$init" ;;
  # Stage 1 on ds-s2 (a new person in every training recording, framed dancers, ds-s1's
  # empty scenes), warm-started from mask-s2: the test cast wears what no ds-s1 character did.
  train-mask-looks)
    DATA=$DATA_LOOKS train mask mask-looks "${MASK_LOOKS_STEPS:-1200}" --lr 3e-4 --init "$RUNS/mask-s2/best.h5" ;;
  # Stage 1 again from the shipped mask net (issue 7's, the presence net of models/default.h5)
  # on ds-s2's dancer and empty scenes, in windows of one frame (--mask-frames 1): the U-Net
  # sees one frame at a time, so 32 one-frame windows a step are 32 samples where 8 windows
  # of 8 frames were 8 (5.7x the distinct windows per second measured). Its runs before
  # (mask-s2, mask-looks) saw 4000 windows in 2 CPU-hours and reached IoU 0.46. Run
  # 2026-11-27 (init: commit 4ada6c1's default): stopped at step 1253 (1.56 CPU-h; its 22 MB
  # state stays in $RUNS), val IoU 0.50, presence 97.2% / 16.8% of val dancer / empty ticks:
  # its mask group is models/default.h5's.
  train-mask-looks2)
    DATA=$DATA_LOOKS BATCH=32 train mask mask-looks2 "${MASK_LOOKS2_STEPS:-1500}" --lr 5e-4 --mask-frames 1 \
      --init "${MASK_LOOKS2_INIT:-models/default.h5}" ;;
  # Stage 1 on ds-s3, from the shipped mask net (mask-looks2's step 1253): at 4 DN the
  # low-light dancer recordings labelled masks on what was sensor noise, so stage 1 learned
  # to see dancers in noise (50% of ds-s3's low-light empty val ticks say "person"); in
  # ds-s3 those dancers show. A short cosine that fits a session at one thread.
  train-mask-s3)
    DATA=$DATA_S3 BATCH=32 train mask mask-s3 "${MASK_S3_STEPS:-800}" --lr 3e-4 --mask-frames 1 \
      --init "${MASK_S3_INIT:-models/default.h5}" ;;
  # The same on ds-s4 (ds-s3 and 32 furnished rooms, most filmed by a sweeping camera):
  # mask-s3 stopped for it once the rooms were made.
  train-mask-s4)
    DATA=$DATA_S4 BATCH=32 train mask mask-s4 "${MASK_S4_STEPS:-600}" --lr 3e-4 --mask-frames 1 \
      --init "${MASK_S4_INIT:-models/default.h5}" ;;
  # Stage 1 again, from the shipped mask net (MASK_S5_INIT: `git show c367f95:models/default.h5`,
  # whose mask net is mask-s4's final step) on ds-s5: rooms and dancers among furniture.
  # The shipped pose net on ds-s5 (ds-s3's dancers and dancers among furniture), a short
  # cosine as pose-s3 on ds-s3: the control of the warp A/B below.
  train-pose-s5)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S5 train pose pose-s5 \
      "${POSE_S5_STEPS:-1000}" --occlusion --lr 3e-4 --init "${POSE_S5_INIT:-models/default.h5}" ;;
  # The same with --warp (a random similarity per window: scale 0.8-1.25, roll +-15 deg,
  # shift +-10%): the net memorises its recordings (fit16: 101 mm on 16 it trained on, at the
  # floor on new people), and the warp makes every window a new picture of its pose.
  train-pose-s5-warp)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S5 train pose pose-s5-warp \
      "${POSE_S5_STEPS:-1000}" --occlusion --warp --lr 3e-4 --init "${POSE_S5_INIT:-models/default.h5}" ;;
  # Both side by side, one thread each: the same windows, steps and schedule. Run 2026-11-28
  # (init: commit 7f069ff's default): ds-s5 val 204.9 mm (control) and 209.0 (warp) against
  # the init's 217.2; paired by recording +3.6 +- 4.2 mm for the warp (models/README).
  ab-warp)
    "$0" train-pose-s5 &
    "$0" train-pose-s5-warp &
    wait ;;
  train-mask-s5)
    DATA=$DATA_S5 BATCH=32 train mask mask-s5 "${MASK_S5_STEPS:-500}" --lr 3e-4 --mask-frames 1 \
      --init "${MASK_S5_INIT:-models/default.h5}" ;;
  # mask-s5 trained on (its validation IoU still rose at its last step): 800 more steps on
  # ds-s5, lr 2e-4 cosine.
  train-mask-s6)
    DATA=$DATA_S5 BATCH=32 train mask mask-s6 "${MASK_S6_STEPS:-800}" --lr 2e-4 --mask-frames 1 \
      --init "${MASK_S6_INIT:-$RUNS/mask-s5/final.h5}" ;;
  # Stage 1's false alarms are whole empty rooms where it draws a dancer-sized blob for
  # seconds (test-s7: 8.9% of empty ticks called person; 2% asked). An A/B from the shipped
  # mask net (mask-s5), the same windows, steps and schedule, one thread each side by side:
  # the control, and windows showing nobody weighted 3x in the loss (--empty-weight 3: a
  # third of ds-s5's training recordings have nobody, so they carry 60% of the loss).
  # Run 2026-11-28 (ninth session; 0.64 CPU-h each): ds-s5 val, each calibrated, dancer /
  # empty ticks called person 97.1% / 4.7% (control) and 96.5% / 4.4% (weighted), the shipped
  # 96.8% / 4.7%: the weight trades one for the other; one low-light room is most of the
  # false alarms of every net (models/README).
  train-mask-s7)
    DATA=$DATA_S5 BATCH=32 train mask mask-s7 "${MASK_S7_STEPS:-500}" --lr 2e-4 --mask-frames 1 \
      --init "${MASK_S7_INIT:-models/default.h5}" ;;
  train-mask-s7-empty)
    DATA=$DATA_S5 BATCH=32 train mask mask-s7-empty "${MASK_S7_STEPS:-500}" --lr 2e-4 --mask-frames 1 \
      --empty-weight "${EMPTY_WEIGHT:-3}" --init "${MASK_S7_INIT:-models/default.h5}" ;;
  ab-empty)
    "$0" train-mask-s7 &
    "$0" train-mask-s7-empty &
    wait ;;
  # Stage 1 on ds-s6 (ds-s5 with twice the training scenes with nobody and three times the
  # validation ones): test-s8's false alarms are moving objects and rooms under a sweeping
  # camera in high light, a kind ds-s5 holds a handful of. From the control mask-s7, 32
  # one-frame windows a step, lr 2e-4 cosine; alone on the machine: THREADS=2.
  train-mask-s8)
    DATA=$DATA_S6 BATCH=32 train mask mask-s8 "${MASK_S8_STEPS:-500}" --lr 2e-4 --mask-frames 1 \
      --init "${MASK_S8_INIT:-$RUNS/mask-s7/final.h5}" ;;
  # mask-s9: mask-s8 on with the soft Dice loss beside the BCE (the IoU's own measure).
  train-mask-s9)
    DATA=$DATA_S6 BATCH=32 EPOCH_STEPS=100 train mask mask-s9 "${MASK_S9_STEPS:-400}" --lr 2e-4 --mask-frames 1 \
      --dice-weight "${MASK_S9_DICE:-1}" --init "${MASK_S9_INIT:-$RUNS/mask-s8/final.h5}" ;;
  # mask-s10: the shipped stage 1 (mask-s8) on for 1000 more steps on ds-s6 at half the rate
  # (mask-s8's validation loss still fell over its last 250 steps); BCE alone (mask-s9's Dice
  # bought nothing).
  train-mask-s10)
    DATA=$DATA_S6 BATCH=32 train mask mask-s10 "${MASK_S10_STEPS:-1000}" --lr 1e-4 --mask-frames 1 \
      --init "${MASK_S10_INIT:-$RUNS/mask-s8/final.h5}" ;;
  # mask-s10-wpv15: mask-s10's recipe reading 15 windows a recording visit instead of 8 (28%
  # less time a step on ds-s6). Run 2026-11-28 with --stop-at 250, then 500 (STOP_AT=N):
  # no accuracy lost against mask-s10 at the same steps (models/README, thirteenth session).
  train-mask-s10-wpv15)
    DATA=$DATA_S6 BATCH=32 train mask mask-s10-wpv15 "${MASK_S10_STEPS:-1000}" --lr 1e-4 --mask-frames 1 \
      --windows-per-visit 15 ${STOP_AT:+--stop-at "$STOP_AT"} --init "${MASK_S10_INIT:-$RUNS/mask-s8/final.h5}" ;;
  # mask-s11: mask-s10 with the geometric augmentation (--warp moves the masks with the
  # input): the same start, rate and steps, so the two compare. The mask net scores IoU 0.79
  # on its own training recordings against 0.70 on validation (dancers, 2026-11-28): the gap,
  # not the fit, is what stands between it and 0.8. Run 2026-11-28 to step 516: worse than
  # mask-s10 at steps 250 and 500 (validation IoU 0.575 against 0.662 at the cut 0.1), so
  # stopped. On a new machine mask-s8's weights are the mask group of the twelfth session's
  # default (git show 1943285:models/default.h5 > F; MASK_S11_INIT=F); the losses repeat.
  train-mask-s11)
    DATA=$DATA_S6 BATCH=32 train mask mask-s11 "${MASK_S11_STEPS:-1000}" --lr 1e-4 --mask-frames 1 --warp \
      --init "${MASK_S11_INIT:-$RUNS/mask-s8/final.h5}" ;;
  # mask-s12: mask-s10-wpv15's recipe with --flip (half the windows mirrored left to right:
  # exact, where --warp resampled the TORE and lost IoU): the same start, rate, steps and
  # validation windows, so the two compare step for step. The right views score IoU 0.585 on
  # test-s8 against the left's 0.819. MASK_S12_INIT as MASK_S11_INIT above.
  train-mask-s12)
    DATA=$DATA_S6 BATCH=32 train mask mask-s12 "${MASK_S12_STEPS:-1000}" --lr 1e-4 --mask-frames 1 \
      --windows-per-visit 15 --flip ${STOP_AT:+--stop-at "$STOP_AT"} --init "${MASK_S12_INIT:-$RUNS/mask-s8/final.h5}" ;;
  # mask-s15: stage 1 at width 0.375 (24 channels at the top, not 16), started from the
  # shipped mask-s10 widened so that it computes what mask-s10 computes (yelan weights widen:
  # the new channels drawn, every weight from them into an old channel zero), then mask-s12's
  # recipe (15 windows a visit, --flip). The mask net scores IoU 0.79 on its own training
  # recordings: capacity is part of its gap. MASK_S15_FROM: a weights file whose mask group is
  # mask-s10 (git show d338ac1:models/default.h5 > F).
  train-mask-s15)
    init="$RUNS/mask-s15-init.h5"
    [ -f "$init" ] || "$Y" weights widen --weights "${MASK_S15_FROM:?a weights file holding mask-s10}" \
      --config benchmarks/configs/small-mask0.375-pose0.125.json --seed 15 -o "$init"
    CFG=benchmarks/configs/small-mask0.375-pose0.125.json DATA=$DATA_S6 BATCH=32 train mask mask-s15 "${MASK_S15_STEPS:-1000}" \
      --lr 1e-4 --mask-frames 1 --windows-per-visit 15 --flip ${STOP_AT:+--stop-at "$STOP_AT"} --init "$init" ;;
  # mask-s16: mask-s15 (width 0.375) on ds-s7, whose training split holds 120 dancers in
  # furnished rooms (ds-s6: 24), most filmed by a moving camera: mask-s15 gained its whole
  # IoU over mask-s10 on such recordings (0.215 -> 0.385 on ds-s6 validation's 4) while it
  # trained on 15 of them. The same recipe as mask-s15 (rate, steps, windows a visit, --flip)
  # from its final weights; screened on ds-s6's validation split (a subset of ds-s7's), so it
  # compares with every earlier stage 1. MASK_S16_INIT: mask-s15's final weights.
  train-mask-s16)
    CFG=benchmarks/configs/small-mask0.375-pose0.125.json DATA=$DATA_S7 BATCH=32 train mask mask-s16 "${MASK_S16_STEPS:-1000}" \
      --lr 1e-4 --mask-frames 1 --windows-per-visit 15 --flip ${STOP_AT:+--stop-at "$STOP_AT"} \
      --init "${MASK_S16_INIT:-$RUNS/mask-s15/final.h5}" ;;
  # Session 2026-11-30 (twenty-first): stage 1 at a quarter of the pixels. Stage 1 is 28 ms of
  # a run on one core against 3.3 for stage 2, and every early-exit setting trades against it
  # (the default: 100-115 poses/s at beta 0.94; issue 16 asks 150). mask.pool 2 runs the same
  # U-Net on the input average-pooled 2 x 2 and resizes its logits back: 9 ms a run, the same
  # parameters. mask-s21-pool2 fine-tunes the default's mask net (mask-s15's final weights) so,
  # with mask-s16's recipe on ds-s7: mask-s16 (MASK_S16_INIT=models/default.h5 where runs/
  # mask-s15 is gone) is its control at full resolution.
  # MASK_S21_LR: the rate (default mask-s16's 1e-4).
  train-mask-s21-pool2)
    CFG=benchmarks/configs/small-mask0.375p2-pose0.125-masked-reuse.json DATA=$DATA_S7 BATCH=32 train mask mask-s21-pool2 \
      "${MASK_S21_STEPS:-1000}" --lr "${MASK_S21_LR:-1e-4}" --mask-frames 1 --windows-per-visit 15 --flip \
      ${STOP_AT:+--stop-at "$STOP_AT"} --init "${MASK_S21_INIT:-models/default.h5}" ;;
  # Session 2026-11-29 (seventeenth): the pose net again, after eight sessions on stage 1.
  # A body filling the frame spans 16 cells of the 17 x 22 heatmaps (106 mm a cell), and the
  # net's image error on recordings it memorised (fit16) stays at 7-13 px: does resolution
  # bound the 2D precision? pose-s17: pose-s5 (1000 steps on ds-s5, 12 mm better than the
  # shipped pose net on ds-s5's validation, never shipped) 1000 more steps on ds-s7's 320
  # dancer recordings; pose-s17-s4: the same from the same weights at pose.head_stride 4
  # (33 x 44 heatmaps, the same parameters). Side by side at one thread each: ab-pose-s17.
  train-pose-s17)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S7 train pose pose-s17 "${POSE_S17_STEPS:-1000}" \
      --occlusion --lr 3e-4 --init "${POSE_S17_INIT:-models/campaign/pose-s5/checkpoint.h5}" ;;
  train-pose-s17-s4)
    CFG=benchmarks/configs/small-pose0.125-nomask-s4.json DATA=$DATA_S7 train pose pose-s17-s4 "${POSE_S17_STEPS:-1000}" \
      --occlusion --lr 3e-4 --init "${POSE_S17_INIT:-models/campaign/pose-s5/checkpoint.h5}" ;;
  ab-pose-s17)
    "$0" train-pose-s17 &
    "$0" train-pose-s17-s4 &
    wait ;;
  # Next: does remixing arms carry to held-out motion? pose-s17 (ds-s7) 3000 more steps on
  # ds-s8 (ds-s7 and its remixed half) against the same on ds-s7, one thread each: ab-remix.
  train-pose-s18-remix)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S8 train pose pose-s18-remix "${POSE_S18_STEPS:-3000}" \
      --occlusion --lr 3e-4 --init "${POSE_S18_INIT:-models/campaign/pose-s17/checkpoint.h5}" ;;
  train-pose-s18-ctl)
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA=$DATA_S7 train pose pose-s18-ctl "${POSE_S18_STEPS:-3000}" \
      --occlusion --lr 3e-4 --init "${POSE_S18_INIT:-models/campaign/pose-s17/checkpoint.h5}" ;;
  ab-remix)
    "$0" train-pose-s18-remix &
    "$0" train-pose-s18-ctl &
    wait ;;
  # Stage 2 behind stage 1's masks (2026-11-29, eighteenth session): pose-s17 (trained on the
  # whole TORE) scored behind mask-s15's masks on ds-s7's furnished rooms was 44 mm better than
  # on the whole TORE. Trained behind the frozen shipped mask net's own masks (what yelan run
  # feeds it) against behind the true masks, 1500 steps each from pose-s17 on ds-s7: ab-mask.
  train-pose-s19-netmask)
    masked_pose pose-s19-netmask "${POSE_S19_STEPS:-1500}" "${POSE_S19_INIT:-models/campaign/pose-s17/checkpoint.h5}" \
      --mask-weights "${POSE_S19_MASK:-models/default.h5}" ;;
  train-pose-s19-truemask)
    masked_pose pose-s19-truemask "${POSE_S19_STEPS:-1500}" "${POSE_S19_INIT:-models/campaign/pose-s17/checkpoint.h5}" ;;
  # pose-s19-truemask's 1500 steps took 20 mm off pose-s17 behind the shipped stage 1 and were
  # still falling: 2000 more, the same recipe.
  train-pose-s20-truemask)
    masked_pose pose-s20-truemask "${POSE_S20T_STEPS:-2000}" "${POSE_S20T_INIT:-models/campaign/pose-s19-truemask/checkpoint.h5}" ;;
  # pose-s19-netmask beat pose-s17 by 27 mm as deployed (behind the shipped stage 1) and
  # pose-s19-truemask by 8: 2000 more steps behind the frozen mask net, the same recipe.
  train-pose-s20-netmask)
    masked_pose pose-s20-netmask "${POSE_S20N_STEPS:-2000}" "${POSE_S20N_INIT:-models/campaign/pose-s19-netmask/checkpoint.h5}" \
      --mask-weights "${POSE_S20N_MASK:-models/default.h5}" ;;
  # As deployed (yelan eval --run) pose-s19-netmask's gain needs fresh masks: at the shipped
  # beta 0.9 stage 1 runs on 1 tick in 10 and stage 2 reads its future masks between runs,
  # which it never trained behind (2026-11-29, nineteenth session). 1000 steps from it behind
  # the frozen mask net's masks reused as early exit reuses them (--mask-reuse 16).
  train-pose-s21-reuse)
    masked_pose pose-s21-reuse "${POSE_S21_STEPS:-1000}" "${POSE_S21_INIT:-models/campaign/pose-s19-netmask/checkpoint.h5}" \
      --mask-weights "${POSE_S21_MASK:-models/default.h5}" --mask-reuse "${POSE_S21_REUSE:-16}" ;;
  # pose-s21-reuse learned behind reused masks cut at 0.5, and the default reads them cut at
  # run.mask_cut_reused 0.35 (nineteenth session): 1000 more steps under the default's config.
  train-pose-s22-reuse)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse.json DATA=$DATA_S7 train pose pose-s22-reuse \
      "${POSE_S22_STEPS:-1000}" --occlusion --lr 3e-4 --init "${POSE_S22_INIT:-models/campaign/pose-s21-reuse/checkpoint.h5}" \
      --mask-weights "${POSE_S22_MASK:-models/default.h5}" --mask-reuse "${POSE_S22_REUSE:-16}" ;;
  # Remixed arms behind stage 1's masks (2026-11-30, twenty-third session): ab-remix (whole
  # TORE) was paused at step 605 within noise; the shipped stage 2 now reads stage 1's masks.
  # pose-s22-reuse is the control: the same recipe on ds-s7 (+0.9 +- 1.7 mm, no change).
  train-pose-s23-remix)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse.json DATA=$DATA_S8 train pose pose-s23-remix \
      "${POSE_S23_STEPS:-1000}" --occlusion --lr 3e-4 --init "${POSE_S23_INIT:-models/campaign/pose-s21-reuse/checkpoint.h5}" \
      --mask-weights "${POSE_S23_MASK:-models/default.h5}" --mask-reuse "${POSE_S23_REUSE:-16}" ;;
  # Free arms behind stage 1's masks (2026-11-30, twenty-fourth session): the recipe of
  # pose-s23-remix and its control pose-s22-reuse exactly, on ds-s9.
  train-pose-s24-free)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse.json DATA=$DATA_S9 train pose pose-s24-free \
      "${POSE_S24_STEPS:-1000}" --occlusion --lr 3e-4 --init "${POSE_S24_INIT:-models/campaign/pose-s21-reuse/checkpoint.h5}" \
      --mask-weights "${POSE_S24_MASK:-models/default.h5}" --mask-reuse "${POSE_S24_REUSE:-16}" ;;
  # Stage 2 twice as wide (pose.width_mult 0.25, hidden 32), widened from the default's
  # stage 2 (the same outputs), then pose-s24-free's recipe exactly: 1000 steps on ds-s9,
  # lr 3e-4 cosine, behind the default's stage 1 and its reused masks. Width is the only
  # difference from pose-s24-free (twenty-fifth session).
  train-pose-s25-wide)
    WIDE_CFG=benchmarks/configs/small-mask0.375-pose0.25-masked-reuse-b094-crop8.json
    [ -f "$RUNS/pose-s25-wide-init.h5" ] ||
      "$Y" weights widen --weights "${POSE_S25_FROM:-$(default_s25)}" --config "$WIDE_CFG" -o "$RUNS/pose-s25-wide-init.h5"
    CFG=$WIDE_CFG DATA=$DATA_S9 train pose pose-s25-wide "${POSE_S25_STEPS:-1000}" --occlusion --lr 3e-4 \
      --init "$RUNS/pose-s25-wide-init.h5" --mask-weights "${POSE_S25_MASK:-$(default_s25)}" --mask-reuse 16 ;;
  # The stick-figure diagnostic (benchmarks/training/stick_figure.py): the same labels, the
  # events those of the projected skeleton alone, the masks the whole frame. STICK_VAL: ds-s7's
  # 56 validation dancers (ds7val-dancers, made by the twentieth session's reproduce block).
  stick-data)
    /usr/bin/python3 benchmarks/training/stick_figure.py "${STICK_VAL:-/var/tmp/yelan-data/ds7val-dancers}" "$DATA_STICK/val"
    /usr/bin/python3 benchmarks/training/stick_figure.py --dancers-only "$DATA_S9/train" "$DATA_STICK/train" ;;
  # train-stick-init: stage 2 from the default's; train-stick-scratch: from a random init.
  train-stick-init)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16.json DATA=$DATA_STICK/train \
      train pose stick-init "${STICK_STEPS:-1500}" --val-data "$DATA_STICK/val" --lr 1e-3 --init $(default_s25) ;;
  train-stick-scratch)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16.json DATA=$DATA_STICK/train \
      train pose stick-scratch "${STICK_STEPS:-1500}" --val-data "$DATA_STICK/val" --lr 1e-3 ;;
  # train-stick-skip: train-stick-init's recipe with pose.hourglass_skip (the hourglasses'
  # mid resolution added past their bottleneck); the same tensors, the default's to start.
  train-stick-skip)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-hgskip.json DATA=$DATA_STICK/train \
      train pose stick-skip "${STICK_STEPS:-1500}" --val-data "$DATA_STICK/val" --lr 1e-3 --init $(default_s25) ;;
  # The stick diagnostic made from nothing (2026-12-01, twenty-seventh session, a new machine):
  # sk-src holds 160 training dancers (half with free arms) and ds-s7's 56 validation dancers
  # (17 min on two cores), drawn as stick figures in sk.
  stick-data-s27)
    "$Y" sim --dataset "$DATA_SK_SRC" --seed 1 --train 160 --val 32 --test 0 --train-empty 0 --val-empty 0 --duration 5s \
      --random-looks --frame-dancer --train-rooms 0 --val-rooms 0 --train-dancer-rooms 0 --val-dancer-rooms 24 \
      --free-arms 0.5 --threads "${THREADS:-2}"
    for split in train val; do
      /usr/bin/python3 benchmarks/training/stick_figure.py "$DATA_SK_SRC/$split" "$DATA_SK/$split"
    done ;;
  # sk-base: the default's stage 2 from a random init on sk (STICK_CFG: another config,
  # SK_NAME the run's name); sk-frame: the same with every window zoomed onto its dancer
  # (--frame-zoom: the oracle crop), training and validation.
  train-sk-base) sk_run sk-base "$DATA_SK" ;;
  train-sk-frame) sk_run sk-frame "$DATA_SK" --frame-zoom ;;
  # Sided sticks (stick_figure.py --sided: the right side's bones ON events, the left's OFF):
  # a plain stick figure from the back is the front's mirror image, so a net can only hedge
  # between the hands; sk-sided asks whether telling the sides apart is what holds it.
  stick-data-sided)
    for split in val train; do
      /usr/bin/python3 benchmarks/training/stick_figure.py --sided "$DATA_SK_SRC/$split" "$DATA_SKS/$split"
    done ;;
  train-sk-sided) sk_run sk-sided "$DATA_SKS" ;;
  # sk-swap: sk-base with --swap-loss (each window scored against its joints or the left/right-
  # traded ones, whichever the net is nearer to): can a net excused from telling the sides
  # apart place the limbs?
  train-sk-swap) sk_run sk-swap "$DATA_SK" --swap-loss ;;
  # The same recipe on the events the sticks were drawn from (sk-src: the same dancers, views,
  # motions and labels; the simulator's faces and shirt fronts are all that tells a front from
  # a back): does a net see the sides in events, and does --swap-loss change that?
  train-ev-base) sk_run ev-base "$DATA_SK_SRC" ;;
  train-ev-swap) sk_run ev-swap "$DATA_SK_SRC" --swap-loss ;;
  # ev-from-sided: ev-base's recipe from sk-sided's weights at its step 4000 (its committed
  # checkpoint) instead of a random init: does a net that reads sided sticks, limb by limb,
  # read the events those sticks were drawn from any better?
  train-ev-from-sided) sk_run ev-from-sided "$DATA_SK_SRC" --init "${EV_INIT:-models/campaign/sk-sided/checkpoint.h5}" ;;
  # sk-src-fp2: sk-src's dancers, motions, views and looks with every front cue at scale 2
  # (--front-print 2: the chest print over most of the chest, the brow band twice as tall);
  # ev-fp2: ev-from-sided's recipe on it. Is a weak cue what keeps the sides from the events?
  ev-data-fp2)
    "$Y" sim --dataset "$DATA_SK_FP2" --seed 1 --train 160 --val 32 --test 0 --train-empty 0 --val-empty 0 --duration 5s \
      --random-looks --frame-dancer --train-rooms 0 --val-rooms 0 --train-dancer-rooms 0 --val-dancer-rooms 24 \
      --free-arms 0.5 --front-print 2 --threads "${THREADS:-2}" ;;
  train-ev-fp2) sk_run ev-fp2 "$DATA_SK_FP2" --init "${EV_INIT:-models/campaign/sk-sided/checkpoint.h5}" ;;
  # sk-fpr: 320 new training dancers (seed 2: none of sk-src's recordings; 80 of them in
  # furnished rooms, as a third of the validation's are), each drawing its front cues' scale
  # in 0.5-2 (--front-print 0.5-2: the cue at every strength, not one outfit); sk-fpr-mix adds
  # sk-src-fp2's 160 (hard links, prefixed). ev-fpr: ev-fp2 (its step 4000) trained on the mix,
  # lr 5e-4 cosine, validated on sk-src-fp2's val as before (scored after on sk-src's too).
  ev-data-fpr)
    "$Y" sim --dataset "$DATA_FPR" --seed 2 --train 240 --train-dancer-rooms 80 --val 0 --test 0 --duration 5s \
      --random-looks --frame-dancer --free-arms 0.5 --front-print 0.5-2 --threads "${THREADS:-2}"
    mkdir -p "$DATA_FPR_MIX/train"
    for f in "$DATA_FPR"/train/*.yelan.h5; do ln -f "$f" "$DATA_FPR_MIX/train/s2-${f##*/}"; done
    for f in "$DATA_SK_FP2"/train/*.yelan.h5; do ln -f "$f" "$DATA_FPR_MIX/train/s1-${f##*/}"; done ;;
  # Stage 1's negatives for a fine-tune on the new dancers (thirty-second session): behind
  # stage 1's masks every stage 2 of the campaign is back at the per-view floor (ev-fpr 202.7
  # mm, the default 202.5, floor 189.3), most of the loss on seven validation recordings where
  # the mask fails (IoU under 0.45: lamps sweeping, a panning camera, flicker among furniture).
  # sk-neg: empty scenes and furnished rooms with nobody in them (seed 3); sk-mask-mix: the
  # 480 training dancers of sk-fpr-mix with sk-neg's training scenes, sk-src-fp2's 56
  # validation dancers with sk-neg's validation scenes (hard links).
  ev-data-neg)
    data_neg
    mkdir -p "$DATA_MASK_MIX/train" "$DATA_MASK_MIX/val"
    ln -f "$DATA_FPR_MIX"/train/*.yelan.h5 "$DATA_NEG"/train/*.yelan.h5 "$DATA_MASK_MIX/train/"
    ln -f "$DATA_SK_FP2"/val/*.yelan.h5 "$DATA_NEG"/val/*.yelan.h5 "$DATA_MASK_MIX/val/" ;;
  # Everything the runs since the thirty-second session read, made from nothing (the thirty-
  # fourth session's machine had an empty /var/tmp): sk-src's validation dancers (the cast's
  # own cue; members are drawn by seed, split and index, so --train 0 leaves them as they
  # were), sk-src-fp2, sk-fpr and its mix, sk-neg and sk-mask-mix. Every step resumes.
  data-s34)
    "$Y" sim --dataset "$DATA_SK_SRC" --seed 1 --train 0 --val 32 --test 0 --train-empty 0 --val-empty 0 --duration 5s \
      --random-looks --frame-dancer --train-rooms 0 --val-rooms 0 --train-dancer-rooms 0 --val-dancer-rooms 24 \
      --free-arms 0.5 --threads "${THREADS:-2}"
    "$0" ev-data-fp2
    "$0" ev-data-fpr
    "$0" ev-data-neg ;;
  # Only what validation and calibration read (forty-fourth session, a new machine again):
  # sk-src's and sk-src-fp2's 56 validation dancers and sk-neg's 48 validation scenes, linked
  # into sk-mask-mix/val; about 15 min on two cores against data-s34's hour.
  val-data)
    for d in "$DATA_SK_SRC" "$DATA_SK_FP2 --front-print 2"; do
      # shellcheck disable=SC2086  # the folder and, for sk-src-fp2, its flag
      "$Y" sim --dataset $d --seed 1 --train 0 --val 32 --test 0 --train-empty 0 --val-empty 0 --duration 5s \
        --random-looks --frame-dancer --train-rooms 0 --val-rooms 0 --train-dancer-rooms 0 --val-dancer-rooms 24 \
        --free-arms 0.5 --threads "${THREADS:-2}"
    done
    "$Y" sim --dataset "$DATA_NEG" --seed 3 --train 0 --val 0 --test 0 --train-empty 0 --val-empty 24 \
      --train-rooms 0 --val-rooms 24 --duration 5s --threads "${THREADS:-2}"
    mkdir -p "$DATA_MASK_MIX/val"
    ln -f "$DATA_SK_FP2"/val/*.yelan.h5 "$DATA_NEG"/val/*.yelan.h5 "$DATA_MASK_MIX/val/" ;;
  # mask-s32: the shipped stage 1 fine-tuned on sk-mask-mix with mask-s16's recipe (batch 32,
  # one mask frame, 15 windows a visit, mirrored, lr 1e-4 cosine).
  train-mask-s32)
    CFG=benchmarks/configs/small-mask0.375-pose0.125.json DATA=$DATA_MASK_MIX/train BATCH=32 train mask mask-s32 \
      "${MASK_S32_STEPS:-1000}" --val-data "$DATA_MASK_MIX/val" --lr 1e-4 --mask-frames 1 --windows-per-visit 15 --flip \
      --init $(default_s25) ;;
  # mask-s36: mask-s32 trained 1000 steps more by its own recipe from a fresh cosine (lr 1e-4),
  # its windows drawn anew (--seed 2): its validation IoU rose 0.674 -> 0.692 over its last 500
  # steps as the rate fell; is there more? Yes, a little: validation IoU 0.716/0.764/0.759 at cuts
  # 0.1/0.3/0.5 against 0.691/0.757/0.766; on sk-src's 56 dancers 0.755 against 0.740 (the
  # default since the forty-first session: ship-s41).
  train-mask-s36)
    CFG=benchmarks/configs/small-mask0.375-pose0.125.json DATA=$DATA_MASK_MIX/train BATCH=32 train mask mask-s36 \
      "${MASK_S36_STEPS:-1000}" --val-data "$DATA_MASK_MIX/val" --lr 1e-4 --mask-frames 1 --windows-per-visit 15 --flip \
      --seed 2 --init models/campaign/mask-s32/checkpoint.h5 ;;
  # sk-s43 (forty-third session): stage 1's training recordings half as many again, drawn as
  # sk-fpr and sk-neg were (seed 4: none of theirs): 160 dancers, 64 dancers in furnished rooms,
  # 48 empty scenes, 48 furnished rooms. mask-s36 learnt its 608 (training loss 0.12 against
  # 0.155 on validation); do new recordings lift the IoU where more steps did not?
  # sk-mask-mix2: sk-mask-mix's 608 and these 320 (hard links), validation as sk-mask-mix's.
  data-s43)
    "$Y" sim --dataset "$DATA_S43" --seed 4 --train 160 --train-dancer-rooms 64 --train-empty 48 --train-rooms 48 \
      --val 0 --test 0 --duration 5s --random-looks --frame-dancer --free-arms 0.5 --front-print 0.5-2 \
      --threads "${THREADS:-2}"
    mkdir -p "$DATA_MASK_MIX2/train"
    ln -f "$DATA_MASK_MIX"/train/*.yelan.h5 "$DATA_MASK_MIX2/train/"
    for f in "$DATA_S43"/train/*.yelan.h5; do ln -f "$f" "$DATA_MASK_MIX2/train/s4-${f##*/}"; done ;;
  # mask-s43: mask-s36 trained 1000 steps more by its recipe on sk-mask-mix2 (lr 1e-4 cosine,
  # windows drawn by seed 3).
  train-mask-s43)
    mask_recipe mask-s43 "$DATA_MASK_MIX2/train" "${MASK_S43_STEPS:-1000}" 3 models/campaign/mask-s36/checkpoint.h5 ;;
  # sk-s45 (forty-fifth session): stage 1 fails in low light, under flicker and before a
  # sweeping camera (test split of seed 20261228: IoU 0.700 low, 0.665 flicker; 115 of 116
  # false "person" calls in two low-light furnished rooms with a sweeping camera). Seed 5 (no
  # set drew it): a plain share as sk-s43 was drawn (176), then more of what fails: of the
  # next members drawn, only those in low light, with flicker or a sweeping camera (--only;
  # each member as it is without the filter). About 25 min on two cores.
  data-s45)
    "$Y" sim --dataset "$DATA_S45" --seed 5 --train 96 --train-dancer-rooms 32 --train-empty 24 --train-rooms 24 \
      --val 0 --test 0 --duration 5s --random-looks --frame-dancer --free-arms 0.5 --front-print 0.5-2 \
      --threads "${THREADS:-2}"
    "$Y" sim --dataset "$DATA_S45" --seed 5 --train 240 --train-dancer-rooms 160 --train-empty 96 --train-rooms 96 \
      --val 0 --test 0 --duration 5s --random-looks --frame-dancer --free-arms 0.5 --front-print 0.5-2 \
      --only low,flicker,sweep --threads "${THREADS:-2}" ;;
  # mask-s45: mask-s43 trained 600 steps more by its recipe on sk-s45 alone (lr 1e-4 cosine,
  # windows drawn by seed 4), validated on sk-mask-mix's validation as before.
  train-mask-s45)
    mask_recipe mask-s45 "$DATA_S45/train" "${MASK_S45_STEPS:-600}" 4 models/campaign/mask-s43/checkpoint.h5 ;;
  # sk-mask-mix3 (forty-sixth session): mask-s45 forgot the rest on sk-s45 alone, and
  # sk-mask-mix2's 928 take an hour and a half to remake, more than a session has beside its
  # training and CI: sk-neg's 128 training scenes (seed 3; about 17 min) made again, beside
  # sk-s45's 402 (hard links).
  data-s46)
    data_neg
    mkdir -p "$DATA_MASK_MIX3/train"
    for f in "$DATA_NEG"/train/*.yelan.h5; do ln -f "$f" "$DATA_MASK_MIX3/train/s3-${f##*/}"; done
    for f in "$DATA_S45"/train/*.yelan.h5; do ln -f "$f" "$DATA_MASK_MIX3/train/s5-${f##*/}"; done ;;
  # mask-s46: mask-s43 trained 600 steps by its recipe on sk-mask-mix3 (lr 1e-4 cosine, windows
  # drawn by seed 5), validated on sk-mask-mix's validation as before.
  train-mask-s46)
    mask_recipe mask-s46 "$DATA_MASK_MIX3/train" "${MASK_S46_STEPS:-600}" 5 models/campaign/mask-s43/checkpoint.h5 ;;
  # mask-s50 (fiftieth session): mask-s43 trained 600 steps more by its own recipe on its own
  # training set, sk-mask-mix2 (lr 1e-4 cosine, windows drawn by seed 6): do more steps on the
  # full set help, where fine-tunes on a part of it (mask-s45, mask-s46) lost IoU?
  train-mask-s50)
    mask_recipe mask-s50 "$DATA_MASK_MIX2/train" "${MASK_S50_STEPS:-600}" 6 models/campaign/mask-s43/checkpoint.h5 ;;
  # sk-mask-mix4 (fiftieth session): mask-s45 and mask-s46 forgot the rest on sk-s45 without
  # all of sk-mask-mix2; here sk-s45's 402 (low light, flicker, sweeping cameras) beside all
  # of sk-mask-mix2's 928 (hard links; data-s34, data-s43 and data-s45 first).
  data-s50)
    mkdir -p "$DATA_MASK_MIX4/train"
    for f in "$DATA_MASK_MIX2"/train/*.yelan.h5; do ln -f "$f" "$DATA_MASK_MIX4/train/"; done
    for f in "$DATA_S45"/train/*.yelan.h5; do ln -f "$f" "$DATA_MASK_MIX4/train/s5-${f##*/}"; done ;;
  # mask-s51: mask-s50's recipe (mask-s43 + 600 steps, lr 1e-4 cosine) on sk-mask-mix4, windows
  # drawn by seed 7: against mask-s50, what the hard conditions add when nothing is left out.
  train-mask-s51)
    mask_recipe mask-s51 "$DATA_MASK_MIX4/train" "${MASK_S51_STEPS:-600}" 7 models/campaign/mask-s43/checkpoint.h5 ;;
  # mask-s52 (fifty-first session): mask-s51 (0.744 as deployed on the 56, the default 0.738)
  # 600 steps more by the same recipe on the same sk-mask-mix4, windows drawn by seed 8: does a
  # second round on the full set still gain? Needs train-mask-s51's final.h5 in $RUNS.
  train-mask-s52)
    mask_recipe mask-s52 "$DATA_MASK_MIX4/train" "${MASK_S52_STEPS:-600}" 8 "$RUNS/mask-s51/final.h5" ;;
  # mask-s53 (started at the end of the fifty-first session): the shipped mask-s52, 600 steps
  # more by the same recipe on sk-mask-mix4, windows drawn by seed 9.
  train-mask-s53)
    mask_recipe mask-s53 "$DATA_MASK_MIX4/train" "${MASK_S53_STEPS:-600}" 9 models/campaign/mask-s52/checkpoint.h5 ;;
  # mask-s54f (fifty-second session): mask-s53's run (mask-s52 + 600 steps, the same windows
  # by seed 9) with future masks 1..3 weighing in the loss as the current one (--mask-focus 3):
  # early exit under the age cap 3 reuses masks 0..2, which the plain loss weighs at a 16th
  # each. mask-s53 lost IoU as deployed against mask-s52 (0.747 against 0.752).
  train-mask-s54f)
    mask_recipe mask-s54f "$DATA_MASK_MIX4/train" "${MASK_S54_STEPS:-600}" 9 models/campaign/mask-s52/checkpoint.h5 --mask-focus 3 ;;
  # sk-s56 (fifty-sixth session): stage 1 gained from every set of new recordings (mask-s43 on
  # +320, mask-s51/52 on +402) and stopped gaining from more steps on the same 1330 (mask-s53,
  # mask-s54f): a fresh draw of sk-s43's mix (seed 11, no set drew it), four times over, made in
  # quarters so that a set stopped early keeps the mix (members are drawn by seed, split and
  # index: each command adds the next indices; done files are kept). About 25 min a quarter on
  # two cores. Then mask-s57: mask-s52 trained 600 steps on it by its recipe (windows drawn by
  # seed 10; about 55 min on two cores, resumable), scored as deployed against the default.
  data-s56)
    for q in ${S56_QUARTERS:-1 2 3 4}; do
      "$Y" sim --dataset "$DATA_S56" --seed 11 --train $((160 * q)) --train-dancer-rooms $((64 * q)) \
        --train-empty $((48 * q)) --train-rooms $((48 * q)) --val 0 --test 0 --duration 5s --random-looks --frame-dancer \
        --free-arms 0.5 --front-print 0.5-2 --threads "${THREADS:-2}"
    done ;;
  # train-mask-s57 on the first quarter alone (fifty-seventh session): 0.747 as deployed on
  # validation against the default's 0.750; train the next round on every quarter.
  train-mask-s57)
    mask_recipe mask-s57 "$DATA_S56/train" "${MASK_S57_STEPS:-600}" 10 models/campaign/mask-s52/checkpoint.h5 ;;
  # mask-s61n (sixty-first session): the shipped stage 1 cut to width 0.25 (`yelan weights narrow`;
  # 2.06 against 4.60 GFLOP a run, IoU 0.710 untrained against 0.776), trained by the recipe on
  # sk-s56's first quarter (windows drawn by seed 12) at lr 3e-4 (the recipe's 1e-4 fine-tunes a
  # converged net; a third of every layer's inputs is gone here): does a cheaper stage 1 run
  # often enough beat the shipped one reused longer, as deployed? Ran 2160 s at two threads: mask IoU
  # as deployed 0.747 every tick, 0.723 under the cap 3 (the default's 0.722 under the cap 6) at
  # x1.05 its poses/s on Zen 3; validation still rising at the end (models/README, sixty-first).
  train-mask-s61n)
    start=$RUNS/mask0.25-narrowed.h5
    [ -f "$start" ] || "$Y" weights narrow --weights models/default.h5 --config "$NARROW_CFG" -o "$start"
    MASK_CFG=benchmarks/configs/small-pose0.125.json MASK_LR=3e-4 mask_recipe mask-s61n "$DATA_S56/train" "${MASK_S61_STEPS:-600}" 12 "$start" ;;
  # mask-s64n (sixty-fourth session): mask-s61n (its final weights, copied from models/campaign/
  # mask-s61n/checkpoint.h5 where $RUNS has none) trained on by the recipe on sk-s56's first two
  # quarters (640 recordings, 320 of them new to it), windows drawn by seed 17, at the recipe's
  # fine-tune rate 1e-4: its validation IoU still rose when mask-s61n's cosine ended.
  train-mask-s64n)
    start=$RUNS/mask-s61n/final.h5
    [ -f "$start" ] || start=models/campaign/mask-s61n/checkpoint.h5
    MASK_CFG=benchmarks/configs/small-pose0.125.json mask_recipe mask-s64n "$DATA_S56/train" "${MASK_S64_STEPS:-800}" 17 "$start" ;;
  # pose-s62 (sixty-second session): the shipped stage 2 (pose-s35, trained behind mask-s32's
  # reused masks on sk-fpr-mix's 480 recordings) fine-tuned behind the shipped stage 1's reused
  # masks on sk-s56's first-quarter dancers (224 recordings no stage 2 has seen: random looks,
  # free arms on half of them, the front cue drawn 0.5-2, 64 in furnished rooms; its empty
  # scenes would only fill batches, their joints weigh nothing), windows drawn by seed 13.
  train-pose-s62)
    s56_pose pose-s62 "${POSE_S62_STEPS:-2000}" 13 1 ;;
  # pose-s63 (sixty-third session): pose-s62's recipe on twice the recordings (the dancers of
  # sk-s56's first two quarters, 448), windows drawn by seed 14: pose-s62 fitted its 224
  # recordings (-37 mm on them) and nothing held out; does doubling them reach new people?
  train-pose-s63)
    s56_pose pose-s63 "${POSE_S63_STEPS:-2000}" 14 2 --validate-start ;;
  # pose-s63f: the same with the pose net's BatchNorm statistics frozen (--freeze-bn), 1000 steps.
  # pose-s63 went from its start's 185 mm on the trainer's validation to 210 by step 250 (and
  # pose-s62's windows from 187 to 191 in one step at 3e-4; 193 with the statistics frozen, 187
  # at lr 1e-30). Do batches that leave the statistics alone forget less of what held-out
  # dancers need? No: 224 at step 250 (models/README, sixty-third session).
  train-pose-s63f)
    s56_pose pose-s63f "${POSE_S63F_STEPS:-1000}" 14 2 --validate-start --freeze-bn ;;
  # pose-s63-lr3e5 (sixty-third and sixty-fourth sessions): pose-s63 at a tenth of the rate.
  # The trainer's validation 185 (the start) / 189 / 188 / 188 / 193 mm at steps 0-1000; on the
  # 56 validation dancers frame by frame -1.0 +- 1.5 mm against the default: no rate tried keeps
  # the held-out score and gains on it (models/README, sixty-fourth session).
  train-pose-s63-lr3e5)
    POSE_LR=3e-5 s56_pose pose-s63-lr3e5 "${POSE_S63L_STEPS:-1000}" 14 2 --validate-start ;;
  # ev-s64 (sixty-fourth session on): sk-sided's stick net trained on the events of sk-s56's 448
  # dancers by ev-fp2's recipe (lr 1e-3 cosine, true masks, 4000 steps, windows drawn by seed
  # 18): does a fresh stage 2 on three times ev-fp2's dancers reach held-out ones? Its state at
  # step 1130 is in models/campaign/ev-s64 (copied into $RUNS when $RUNS has none).
  train-ev-s64)
    dir=$RUNS/sk-s56-q12-dancers
    s56_dancers "$dir" 2
    if [ ! -f "$RUNS/ev-s64/checkpoint.state" ] && [ -f models/campaign/ev-s64/checkpoint.state ]; then
      mkdir -p "$RUNS/ev-s64" && cp models/campaign/ev-s64/{checkpoint.h5,checkpoint.state,log.csv,run.json} "$RUNS/ev-s64/"
    fi
    CFG=$STICK_CFG0 DATA=$dir THREADS=${THREADS:-2} train pose ev-s64 "${EV_S64_STEPS:-4000}" --val-data "$DATA_SK_FP2/val" \
      --lr 1e-3 --seed 18 --init models/campaign/sk-sided/checkpoint.h5 --validate-start ;;
  train-ev-fpr)
    CFG=$STICK_CFG0 DATA=$DATA_FPR_MIX/train train pose ev-fpr "${FPR_STEPS:-4000}" --val-data "$DATA_SK_FP2/val" --lr 5e-4 \
      --init "${EV_INIT:-models/campaign/ev-fp2/checkpoint.h5}" ;;
  # ev-fpr-s4: the same from the same weights at pose.head_stride 4 (33 x 44 heatmaps, cells of
  # 8 sensor px; the same parameters): ev-fp2 puts both hips, both knees and both feet between
  # the two, 1.5-2 of its 16-px cells apart; do finer maps separate them?
  # ev-fpr-mask: ev-fpr (its step 2000) behind the shipped stage 1's masks, reused as early
  # exit reuses them (the default's recipe, lr 3e-4): as deployed ev-fpr loses 30 mm to stage
  # 1's masks where the default, trained behind them, loses 18.
  train-ev-fpr-mask)
    CFG=$STICK_CFG0 DATA=$DATA_FPR_MIX/train train pose ev-fpr-mask "${FPR_MASK_STEPS:-2000}" --val-data "$DATA_SK_FP2/val" \
      --lr 3e-4 --init "${EV_INIT:-models/campaign/ev-fpr/checkpoint.h5}" --mask-weights $(default_s25) --mask-reuse 16 ;;
  # ev-fpr twice as wide (pose.width_mult 0.25, hidden 32), widened from ev-fpr (the same
  # outputs), then ev-fpr's recipe again: 2000 steps on the 480-recording mix, lr 5e-4 cosine,
  # behind true masks. ev-fpr-more is the control: the same 2000 steps at ev-fpr's width.
  train-ev-fpr-wide)
    WIDE_CFG=benchmarks/configs/small-mask0.375-pose0.25-masked-reuse-b094-crop8-s16.json
    if [ ! -f "$RUNS/ev-fpr-wide-init.h5" ]; then
      "$Y" weights combine --mask $(default_s25) --pose models/campaign/ev-fpr/checkpoint.h5 --config "$STICK_CFG0" \
        -o "$RUNS/ev-fpr-wide-from.h5"
      "$Y" weights widen --weights "$RUNS/ev-fpr-wide-from.h5" --config "$WIDE_CFG" -o "$RUNS/ev-fpr-wide-init.h5"
    fi
    CFG=$WIDE_CFG DATA=$DATA_FPR_MIX/train train pose ev-fpr-wide "${FPR_STEPS:-2000}" --val-data "$DATA_SK_FP2/val" \
      --lr 5e-4 --init "$RUNS/ev-fpr-wide-init.h5" ;;
  train-ev-fpr-more)
    CFG=$STICK_CFG0 DATA=$DATA_FPR_MIX/train train pose ev-fpr-more "${FPR_STEPS:-2000}" --val-data "$DATA_SK_FP2/val" \
      --lr 5e-4 --init models/campaign/ev-fpr/checkpoint.h5 ;;
  # ev-fpr-grow4: ev-fpr-more's recipe with every mask grown by 4 input pixels
  # (run.mask_grow 4, the true ones in training, stage 1's when deployed): ev-fpr-more is its
  # control.
  train-ev-fpr-grow4)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4.json DATA=$DATA_FPR_MIX/train \
      train pose ev-fpr-grow4 "${FPR_STEPS:-2000}" --val-data "$DATA_SK_FP2/val" --lr 5e-4 --init models/campaign/ev-fpr/checkpoint.h5 ;;
  # Stage 2 reading the events outside stage 1's mask (thirty-fourth session): ev-fpr-grow4
  # (its committed step 2000) trained behind the default's stage 1 and its reused masks, grown
  # by 4 pixels, lr 3e-4 cosine (ev-fpr-mask's recipe), gated as it is (pose-s34-gated) or
  # with pose.outside_input (pose-s34-outside: widened first, zero weights on the new
  # channels, so both start from the same outputs). Run the two side by side at one thread.
  train-pose-s34-gated)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4.json DATA=$DATA_FPR_MIX/train \
      train pose pose-s34-gated "${S34_STEPS:-1000}" --val-data "$DATA_SK_FP2/val" --lr 3e-4 \
      --init models/campaign/ev-fpr-grow4/checkpoint.h5 --mask-weights $(default_s25) --mask-reuse 16 ;;
  train-pose-s34-outside)
    OUT_CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4-outside.json
    if [ ! -f "$RUNS/pose-s34-outside-init.h5" ]; then
      "$Y" weights combine --mask $(default_s25) --pose models/campaign/ev-fpr-grow4/checkpoint.h5 \
        --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4.json -o "$RUNS/pose-s34-outside-from.h5"
      "$Y" weights widen --weights "$RUNS/pose-s34-outside-from.h5" --config "$OUT_CFG" -o "$RUNS/pose-s34-outside-init.h5"
    fi
    CFG=$OUT_CFG DATA=$DATA_FPR_MIX/train train pose pose-s34-outside "${S34_STEPS:-1000}" --val-data "$DATA_SK_FP2/val" \
      --lr 3e-4 --init "$RUNS/pose-s34-outside-init.h5" --mask-weights $(default_s25) --mask-reuse 16 ;;
  ab-outside)
    "$0" train-pose-s34-gated &
    "$0" train-pose-s34-outside &
    wait ;;
  # pose-s35: stage 2 for mask-s32 (thirty-fifth session): pose-s34-gated's recipe (ev-fpr-grow4's
  # committed step 2000, 1000 steps, lr 3e-4 cosine, masks grown by 4 pixels) behind mask-s32's
  # own reused masks, on the 480-recording mix. As deployed, mask-s32 behind the default's
  # stage 2 lost 6 mm on common poses to early exit's older masks (thirty-third session).
  train-pose-s35)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4.json DATA=$DATA_FPR_MIX/train \
      train pose pose-s35 "${S35_STEPS:-1000}" --val-data "$DATA_SK_FP2/val" --lr 3e-4 \
      --init models/campaign/ev-fpr-grow4/checkpoint.h5 --mask-weights "${S35_MASK:-$RUNS/mask-s32/final.h5}" --mask-reuse 16 ;;
  # pose-s36: pose-s35 (the default's stage 2 since the thirty-sixth session) 1000 steps more by
  # its own recipe from a fresh cosine, its windows drawn anew (--seed 2): its validation MPJPE
  # was still falling at its last step (188.3 -> 187.2 mm).
  train-pose-s36)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-grow4.json DATA=$DATA_FPR_MIX/train \
      train pose pose-s36 "${S36_STEPS:-1000}" --val-data "$DATA_SK_FP2/val" --lr 3e-4 --seed 2 \
      --init models/campaign/pose-s35/checkpoint.h5 --mask-weights models/campaign/mask-s32/checkpoint.h5 --mask-reuse 16 ;;
  train-ev-fpr-s4)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-stride4.json DATA=$DATA_FPR_MIX/train \
      train pose ev-fpr-s4 "${FPR_STEPS:-4000}" --val-data "$DATA_SK_FP2/val" --lr 5e-4 \
      --init "${EV_INIT:-models/campaign/ev-fp2/checkpoint.h5}" ;;
  # sk-depth: sk-sided's recipe (sided sticks, random init, 1500 steps) with pose.depth_map:
  # does z read off a depth map under each joint's xy map learn the depth the marginals do
  # not (sk-sided: 96.8 mm a joint after aligning the hips' depths, the per-view floor 104.0)?
  # sk-sided-r: sk-sided's first 1500 steps again, the control scored the same way.
  train-sk-depth) STICK_CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-depth.json sk_run sk-depth "$DATA_SKS" ;;
  train-sk-sided-r) sk_run sk-sided-r "$DATA_SKS" ;;
  # pose-s24-free's recipe exactly (1000 steps on ds-s9 behind the default's stage 1 and its
  # reused masks, lr 3e-4, from pose-s21-reuse), with pose.hourglass_skip.
  train-pose-s26-skip)
    CFG=benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s16-hgskip.json DATA=$DATA_S9 \
      train pose pose-s26-skip "${POSE_S26_STEPS:-1000}" --occlusion --lr 3e-4 \
      --init "${POSE_S26_INIT:-models/campaign/pose-s21-reuse/checkpoint.h5}" --mask-weights $(default_s25) --mask-reuse 16 ;;
  ab-mask)
    "$0" train-pose-s19-netmask &
    "$0" train-pose-s19-truemask &
    wait ;;
  # Can the shipped pose net fit 16 recordings? Every 12th dancer recording of ds-s3's
  # training split (16), trained and validated on the same 16 from the shipped net, lr 1e-3
  # cosine. Run 2026-11-27 (MPJPE 90 mm on them at step 250; stopped at 367): it memorises
  # 16 recordings within 250 steps where on all 200 it stays near the per-view floor.
  fit16)
    fit="${FIT16:-/var/tmp/yelan-data/fit16}"
    mkdir -p "$fit/train" "$fit/val"
    ls "$DATA_S3/train" | grep -v -- '-empty-' | awk 'NR % 12 == 1' | head -16 | while read -r f; do
      ln -f "$DATA_S3/train/$f" "$fit/train/"
      ln -f "$DATA_S3/train/$f" "$fit/val/"
    done
    CFG=benchmarks/configs/small-pose0.125-nomask.json DATA="$fit/train" train pose fit16 "${FIT16_STEPS:-3000}" \
      --val-data "$fit/val" --lr 1e-3 --init "${FIT16_INIT:-$(default_s25)}" ;;
  # How many recordings can stage 2 fit? FIT_N of ds-s9's plain training dancers (every
  # k-th, k spreading them over the split), trained and validated on the same FIT_N from the
  # default's stage 2 (FIT_INIT; with FIT_CFG another width, started by weights widen), lr 1e-3
  # cosine, behind the default's stage 1 as deployed; FIT_STEPS defaults to 16 steps a
  # recording (about 125 visits each at batch 8, fit16's), so runs of different FIT_N see
  # each recording as often. Twenty-fifth session: the nets sit at 81% of the per-view floor
  # on their own training recordings while fit16 memorised 16.
  fit-n)
    n="${FIT_N:-64}"
    name="fit-n$n${FIT_TAG:+-$FIT_TAG}"
    fit="/var/tmp/yelan-data/$name"
    mkdir -p "$fit/train" "$fit/val"
    total=$(ls "$DATA_S9/train" | grep -v -- '-empty-\|-room-' | wc -l)
    ls "$DATA_S9/train" | grep -v -- '-empty-\|-room-' | awk -v k=$((total / n)) 'NR % k == 1' | head -"$n" | while read -r f; do
      ln -f "$DATA_S9/train/$f" "$fit/train/"
      ln -f "$DATA_S9/train/$f" "$fit/val/"
    done
    CFG="${FIT_CFG:-benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8.json}" DATA="$fit/train" \
      train pose "$name" "${FIT_STEPS:-$((16 * n))}" --val-data "$fit/val" --lr 1e-3 --init "${FIT_INIT:-$(default_s25)}" \
      --mask-weights $(default_s25) --mask-reuse 16 ;;
  # save: the runs' state into models/campaign/ for a commit (run.json, log.csv, and where
  # small enough the checkpoint: a few MB); restore: back into $RUNS on a new machine.
  # Every run in $RUNS (a fixed list here once left mask-s32 out, and a new machine lost it).
  save)
    for dir in "$RUNS"/*/; do
      run=$(basename "$dir")
      [ -f "$RUNS/$run/run.json" ] || continue
      # A run restarted from scratch on a new machine must not overwrite a longer history.
      if [ -f "models/campaign/$run/log.csv" ] && [ -f "$RUNS/$run/log.csv" ] &&
         [ "$(wc -l < "$RUNS/$run/log.csv")" -lt "$(wc -l < "models/campaign/$run/log.csv")" ]; then
        echo "$run: $RUNS/$run/log.csv is shorter than the committed one; not saved (move one of them aside)" >&2
        continue
      fi
      # A run stopped before its first checkpoint (or whose checkpoint was lost) keeps its log.
      if [ ! -f "$RUNS/$run/checkpoint.h5" ]; then
        echo "$run: no checkpoint in $RUNS/$run; only its log is saved" >&2
        mkdir -p "models/campaign/$run"
        cp "$RUNS/$run/run.json" "$RUNS/$run/log.csv" "models/campaign/$run/" 2>/dev/null || true
        continue
      fi
      mkdir -p "models/campaign/$run"
      cp "$RUNS/$run/run.json" "$RUNS/$run/log.csv" "models/campaign/$run/"
      # The same for its console output: a resumed run's .out on a new machine holds only this session's part.
      if [ -f "$RUNS/$run.out" ] && { [ ! -f "models/campaign/$run/train.out" ] ||
         [ "$(wc -l < "$RUNS/$run.out")" -ge "$(wc -l < "models/campaign/$run/train.out")" ]; }; then
        cp "$RUNS/$run.out" "models/campaign/$run/train.out"
      fi
      size=$(( $(stat -c %s "$RUNS/$run/checkpoint.h5") + $(stat -c %s "$RUNS/$run/checkpoint.state") ))
      # The quarter-width pose net's is 11 MiB (its Adam moments are two thirds of it): kept,
      # since a lost checkpoint cost 2.2 CPU-hours once (pose-small-looks).
      if [ "$size" -le $((12 << 20)) ]; then
        cp "$RUNS/$run/checkpoint.h5" "$RUNS/$run/checkpoint.state" "models/campaign/$run/"
      elif [ -f "$RUNS/$run/final.h5" ] && [ "$(stat -c %s "$RUNS/$run/final.h5")" -le $((12 << 20)) ]; then
        # A finished run's weights without its Adam moments: it cannot resume, but it is not lost.
        cp "$RUNS/$run/final.h5" "models/campaign/$run/"
        echo "$run: checkpoint and state are $((size >> 20)) MiB: only final.h5 copied" >&2
      elif [ -f "$RUNS/$run/final.h5" ] && [ "$(stat -c %s "$RUNS/$run/checkpoint.h5")" -le $((20 << 20)) ]; then
        # A finished stage-1 run: its last checkpoint is the mask net's weights alone (17 MiB at
        # width 0.375; final.h5 adds the stage 2 it started beside). Lost once (mask-s32, 1.8
        # CPU-hours), so kept.
        cp "$RUNS/$run/checkpoint.h5" "models/campaign/$run/"
        echo "$run: checkpoint and state are $((size >> 20)) MiB: only the finished checkpoint.h5 copied" >&2
      else
        echo "$run: checkpoint and state are $((size >> 20)) MiB: not copied (it resumes from $RUNS on this machine)" >&2
      fi
    done ;;
  restore)
    for d in models/campaign/*/; do
      run=$(basename "$d")
      mkdir -p "$RUNS/$run"
      [ -f "$RUNS/$run/checkpoint.state" ] && { echo "$run: $RUNS/$run has a checkpoint already; kept" >&2; continue; }
      cp "$d"* "$RUNS/$run/"
    done ;;
  # The default of 2026-12-02 (thirty-sixth session): mask-s32 (train-mask-s32) and pose-s35
  # (train-pose-s35) in the calibrated -s35 config; the same bytes as the shipped file.
  ship-s36)
    "$Y" weights combine --mask models/campaign/mask-s32/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s35.json -o models/default.h5 ;;
  # The default from the thirty-seventh to the forty-first session: ship-s36's networks and calibration, the
  # skeleton averaged over the ticks (run.pose_tau_s 0.05, chosen on sk-src's validation
  # dancers as deployed).
  ship-s37)
    "$Y" weights combine --mask models/campaign/mask-s32/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s37.json -o models/default.h5 ;;
  # The default since the forty-first session: stage 1 mask-s36 (train-mask-s36), stage 2 pose-s35,
  # presence and depth scale calibrated for mask-s36 (-s41: -s37's settings otherwise).
  ship-s41)
    "$Y" weights combine --mask models/campaign/mask-s36/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s41.json -o models/default.h5 ;;
  # The default since the forty-third session: -s41's networks with early exit capped by age
  # (run.mask_max_age 6), presence and depth scale refitted under it (age43-commands-s43.sh).
  ship-s43)
    "$Y" weights combine --mask models/campaign/mask-s36/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s43.json -o models/default.h5 ;;
  # The default since the forty-fourth session: mask-s43 behind the same stage 2 and age cap,
  # refitted (benchmarks/training/candidate.sh mask-s43-age6-s44 ... chose it on validation).
  ship-s44)
    "$Y" weights combine --mask models/campaign/mask-s43/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s44.json -o models/default.h5 ;;
  # The default since the forty-ninth session: -s44's networks and calibration, stage 1 in bf16
  # on AMX where the CPU has it and there capped at 3 frames (chosen on validation, s49/).
  ship-s49)
    "$Y" weights combine --mask models/campaign/mask-s43/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s49.json -o models/default.h5 ;;
  # The default since the fifty-first session: stage 1 mask-s52 (train-mask-s51, then
  # train-mask-s52) behind -s49's stage 2 and run settings, refitted (candidate.sh mask-s52).
  ship-s51)
    "$Y" weights combine --mask models/campaign/mask-s52/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s51.json -o models/default.h5 ;;
  # The default since the fifty-fourth session: -s51's networks and calibration; where stage 1
  # runs its Winograd GEMMs in bf16 on AVX512-BF16 (no AMX: AMD Zen 4, 5) the age cap is 4.
  ship-s54)
    "$Y" weights combine --mask models/campaign/mask-s52/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s54.json -o models/default.h5 ;;
  ship-s55)
    "$Y" weights combine --mask models/campaign/mask-s52/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s55.json -o models/default.h5 ;;
  # The default since the fifty-eighth session: -s55's, stage 2 in bf16 too on AMX (run.pose_bf16).
  ship-s58)
    "$Y" weights combine --mask models/campaign/mask-s52/checkpoint.h5 --pose models/campaign/pose-s35/checkpoint.h5 \
      --config benchmarks/configs/small-mask0.375-pose0.125-masked-reuse-b094-crop8-s58.json -o models/default.h5 ;;
  combine)
    "$Y" weights combine --mask "$RUNS/${MASK_RUN:-mask-s2}/best.h5" --pose "$RUNS/pose-p0125/best.h5" --config "$CFG" \
      -o models/default.h5 ;;
  all)
    dataset
    "$0" train
    "$0" combine ;;
  help) targets ;;
  *) echo "usage: $0 [$(targets | paste -sd'|')]" >&2; exit 2 ;;
esac
