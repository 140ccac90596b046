// Turning simulator windows into network batches: TORE volumes averaged down to the
// config's input size in the blocked layout, masked (pose stage) by the true mask or a
// frozen mask net's (binarised at 0.1), optional occlusion rectangles, and the targets:
// normalised joints with validity (pose) or current + future masks (mask).
#pragma once
#include <vector>

#include "camera/sim/rng.h"
#include "camera/sim/window_stream.h"
#include "engine/input.h"
#include "engine/mask_net.h"
#include "engine/model_config.h"
#include "engine/train/augment.h"
#include "engine/train/metrics.h"
#include "engine/train/pose_norm.h"
#include "layers/param.h"

namespace yelan::train {

// Early exit as `yelan run` has it, for a window behind a frozen mask net: stage 1 last ran
// `phase` frames before the window's first frame and reruns every `period` frames, and
// frame t reads the future mask of age (t + phase) mod period from the latest run (the
// window's `phase` frames before it are read out for that run), cut at run.mask_cut_reused
// where older than the run. {1, 0}: every frame its own current mask, as without it.
struct MaskReuse {
  int period = 1, phase = 0;
};
// Drawn per window: the period uniform in 1..max_period, the phase uniform below it.
MaskReuse draw_mask_reuse(camera::sim::Rng& r, int max_period);

// none: the mask stage (labels, no masking); unmasked: the pose stage of a config with
// pose.masked_input false (every other source becomes this one for such configs).
enum class MaskSource { none, truth, net, unmasked };

// The network's input planes of one frame: the TORE volume itself, or log(1 + n) of the
// event counts (the "counts" representation) computed into `scratch`.
const std::vector<float>& input_planes(const ModelConfig& cfg, const camera::sim::SimFrame& f, std::vector<float>& scratch);



struct Batch {
  layers::ActBuf input;                    // n = windows x S frames, cfg.channels x H x W
  layers::ActBuf labels;                   // mask stage: n x N masks (frame t + k in channel k)
  std::vector<float> target, valid;  // pose stage: n x 13 x 3 normalised, n x 13
  std::vector<Pose13> truth_mm;      // camera frame, per frame
  std::vector<double> z_ref;         // the head's true depth per frame
  std::vector<std::uint8_t> valid_u8;
  Intrinsics k{};
  int frames = 0;
};

// Frame f of a batch: the network's normalised joints (frames x 13 x 3) denormalised with
// the frame's true head depth (the paper protocol), and which joints count.
Pose13 predicted_pose_mm(const Batch& b, const std::vector<float>& joints_norm, int f);
std::array<std::uint8_t, kJoints> valid_joints(const Batch& b, int f);

class BatchBuilder {
 public:
  // `lead`: frames each window has before the ones that are inputs (a MaskReuse's phase
  // reaches at most that far back); 0 for windows that start with their first input.
  BatchBuilder(const ModelConfig& cfg, int windows, MaskSource source, int lead = 0);
  void clear() { used_ = 0; }
  // Appends one window (after `lead` frames, cfg.window frames are inputs; the mask stage's
  // labels use the frames after them too). `mask_net` runs (frozen) for MaskSource::net only,
  // on every input frame, or as `reuse` says.
  // `warp`: one similarity for the whole window: input, joints and (mask stage) labels.
  // `flip`: then the whole window mirrored left to right (augment.h), the joints with it and
  // left and right swapped.
  void add(const camera::sim::SimWindow& w, MaskNet& mask_net, camera::sim::Rng* occlusion,
           const Similarity* warp = nullptr, bool flip = false, const MaskReuse* reuse = nullptr);
  const Batch& batch() const { return b_; }
  MaskSource source() const { return source_; }

 private:
  ModelConfig cfg_;
  int windows_, lead_, used_ = 0;
  MaskSource source_;
  bool outside_;  // pose.outside_input behind a mask: the input holds [inside | outside]
  Batch b_;
  layers::ActBuf one_;  // one window's unmasked input, for the frozen mask net
  std::vector<float> planes_;  // a frame's count planes (TORE is read in place)
};

}  // namespace yelan::train
