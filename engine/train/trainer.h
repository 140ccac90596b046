// The CPU trainer (SPEC section 6): windows of S frames straight from the simulator (no
// disk) or from labelled recordings on disk, Adam with L2 decay and a step LR schedule,
// validation on other scenes or recordings each epoch with early stopping, occlusion
// augmentation, a CSV log, and atomic checkpoints every few minutes from which --resume
// continues bit-exactly.
//   stage "mask": the U-Net on TORE, labels the current and N-1 future masks.
//   stage "pose": the pose net on masked TORE (the mask from a frozen mask net, or the
//   simulator's true mask when none is given), targets the normalised 3D joints.
#pragma once
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "camera/sim/simulator.h"
#include "engine/adam.h"
#include "engine/model_config.h"

namespace yelan::train {

struct TrainSpec {
  std::string stage = "pose";
  ModelConfig cfg;
  std::vector<camera::sim::SimSpec> scenes, val_scenes;
  // Recordings on disk (*.yelan.h5) instead of the simulator: training and validation
  // files, split by recording (camera::sim::split_by_recording).
  std::vector<std::string> data, val_data;
  std::uint64_t seed = 1;
  int batch = 1;                    // windows per step
  // mask stage: frames per training window (0: the config's window). The U-Net sees one
  // frame at a time, so a window's 8 frames are 8 near-copies of one sample: windows of 1
  // frame give 8x the distinct samples per CPU-second. Validation keeps the config's window.
  int mask_frames = 0;
  std::int64_t steps = 1000;        // the run's length: the LR schedule's horizon
  std::int64_t stop_at = 0;         // > 0: stop after this step with a checkpoint, as an
                                    // interrupted run would (--resume continues the schedule)
  int steps_per_epoch = 50;
  int val_windows = 4;
  int patience = 10;                // epochs without a better validation loss
  AdamOptions adam;
  // "cosine": from adam.lr (after a linear warm-up of warmup_steps) down to lr_min_ratio x
  // adam.lr at `steps`, by steps, so the rate anneals within the run whatever its epochs;
  // "step": halved every adam.step_size epochs (the paper's).
  std::string lr_schedule = "cosine";
  int warmup_steps = 100;
  double lr_min_ratio = 0.02;
  // Recordings: a window's TORE holds the events of up to this long before its first frame
  // (5 s: everything TORE reads, as `yelan run` has it).
  double history_s = 5;
  // Recordings (with history): each visit to a recording serves this many windows, read in
  // one pass (window_stream.h). More windows per visit read the 5 s of history less often
  // (a mask window of 1 frame spans 16 frames of a 245-frame recording, so 15 fit); fewer
  // renew a batch's recordings more often.
  int windows_per_visit = 8;
  // Threads reading a batch's windows from their recordings at once (0: the engine's thread
  // count; 1: one after another). The same windows, value for value, either way.
  int read_threads = 0;
  double checkpoint_minutes = 10;
  bool occlusion = false;           // random rectangles (10-80 px) zeroed in the input
  bool warp = false;                // a random similarity per window, input and targets (augment.h)
  bool flip = false;                // half the windows mirrored left to right, input and targets (augment.h)
  // every window, training and validation, zoomed onto its dancer from the true joints
  // (augment.h framing_similarity): a diagnostic of what heatmap resolution on the dancer buys
  bool frame_zoom = false;
  // each window scored against its joints or with left and right traded, whichever the net
  // is nearer to (hpe_loss's swap_group), training and validation loss; MPJPE stays strict
  bool swap_loss = false;
  // the trained net's BatchNorm layers keep the starting weights' running statistics and
  // normalise by them in training too (a fine-tune in small batches of few recordings: each
  // batch's statistics would otherwise pull the running ones towards its own recordings)
  bool freeze_bn = false;
  float empty_weight = 1;           // mask stage: a window showing nobody weighs this much in
                                    // the loss (nobody_weights); validation is never weighted
  float dice_weight = 0;            // mask stage: the soft Dice term's weight (mask_loss); the
                                    // validation loss leaves it out, comparable across runs
  int mask_focus = 0;               // mask stage: future masks 1..K weigh as the current one
                                    // (mask_loss's focus); validation leaves it out
  std::string mask_weights;         // pose stage: frozen mask net; empty: the true mask
  // pose stage behind mask_weights: > 0, each window masked as early exit in `yelan run`
  // masks it, stage 1 rerun every 1..mask_reuse frames (drawn per window, batch.h
  // MaskReuse), the frames between reading its future masks; 0: a fresh mask every frame.
  int mask_reuse = 0;
  std::string init_weights;         // start from these instead of a random initialisation
  std::string out_dir;
  bool resume = false;
  // validate the starting weights before step 1 and log them as step 0 (not a best.h5 candidate)
  bool validate_start = false;
  double frame_hz = 50;
  bool progress_tty = false;        // a live progress line (else one line per epoch)
  double max_minutes = 0;           // stop (with a checkpoint) after this long; 0: no limit
  double max_cpu_minutes = 0;       // the same in CPU time of this process (all threads): a
                                    // budget that other work on a shared machine does not eat
};

struct TrainResult {
  std::int64_t steps = 0;
  double last_loss = 0, best_val = 0;
  bool early_stopped = false;
  int interrupted = 0;  // the signal (SIGINT, SIGTERM) that stopped the run after a checkpoint
  // This run's part (not resumed ones): training steps' wall time, the share of it spent
  // building batches (reading or simulating windows), CPU seconds, frames trained on.
  double step_s = 0, data_s = 0, cpu_s = 0;
  std::int64_t frames = 0;
};

// Writes out_dir/{log.csv, checkpoint.h5, checkpoint.state, best.h5, final.h5}.
TrainResult train(const TrainSpec& spec, std::ostream& err);

}  // namespace yelan::train
