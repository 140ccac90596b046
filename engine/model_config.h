// Model configurations (weights_tools/configs/*.json; stored verbatim in a weights file's
// `config` attribute). Mirrors weights_tools/reference/config.py: same keys, same checks,
// same channel rounding (round half to even, never below 1).
#pragma once
#include <optional>
#include <stdexcept>
#include <string>

namespace yelan {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct ModelConfig {
  std::string name;
  int channels = 6, sensor_height = 260, sensor_width = 346, downscale = 1, window = 16;
  double mask_width = 1.0;
  int n_masks = 16;
  // mask.pool: stage 1 runs on the input average-pooled k x k (k^2 fewer pixels, its cost
  // divided about so), its mask logits resized back to the input bilinearly; 1: none.
  int mask_pool = 1;
  // mask.crop_margin > 0: at inference, while a dancer is there, stage 1 runs only on the box
  // of its last run's masks (now and the predicted future) grown by this many input pixels
  // (MaskNet::forward_cropped); the whole frame when nobody was there; 0: always the whole frame.
  int mask_crop_margin = 0;
  double pose_width = 1.0;
  int hidden = 128, stages = 3, joints = 13;
  bool bidirectional = true;
  bool convlstm = true;       // pose.convlstm "none": the skip block sees the head's features alone
  bool masked_input = true;   // pose.masked_input false: stage 2 sees the whole input
  // pose.outside_input (not the paper's; default false, needs masked_input): stage 2 reads
  // the input twice, [inside the mask | outside it], 2 x channels in all, the outside part
  // only within the mask's box grown by crop_margin (the crop stage 2 reads; the whole frame
  // at crop_margin 0). A mask that misses a limb no longer hides its events, and a net
  // widened from a gated one (zero weights on the new channels) starts with its outputs.
  bool outside_input = false;
  int pose_channels() const { return outside_input ? 2 * channels : channels; }
  // mask.role: what stage 1 is for. "mask" (the default with masked_input): stage 2 reads the
  // masked TORE. "presence" (needs masked_input false): stage 1 still runs, with early exit,
  // to say whether anyone is there, and stage 2 reads the whole TORE (a mask net's errors
  // then cost no pose accuracy). "none" (the default without masked_input): no stage 1,
  // presence 1 on every tick.
  std::string mask_role = "mask";
  bool runs_stage1() const { return mask_role != "none"; }
  // pose.crop_margin > 0: at inference, stage 2's ResNet head runs only on the mask's
  // bounding box grown by this many input pixels (PoseNet::forward_cropped); 0: whole frame
  int crop_margin = 0;
  // pose.head_stride: the ResNet head's total stride, 8 (torchvision's: layer2 halves) or 4
  // (layer2 keeps layer1's resolution): the heatmaps are then twice as fine in each axis
  // (33 x 44 at input downscale 2), at about three times stage 2's multiply-adds. A body
  // filling the frame spans 16 heatmap cells at stride 8, 106 mm a cell.
  int head_stride = 8;
  // pose.hourglass_skip (not the paper's; default false): each hourglass adds its second
  // block's output (mid resolution) to its up block's, so the heatmaps see the mid resolution
  // past the half-resolution bottleneck; the same parameters.
  bool hourglass_skip = false;
  // pose.depth_map (not the paper's; default false): each stage adds a fourth hourglass whose
  // output is a depth map per joint, and a joint's z is that map averaged under its xy
  // probability map (layers::expected_depth_forward) instead of the zy and xz marginals'
  // coordinates (still trained by their JS terms and read by the next stage's combiner).
  bool depth_map = false;
  // input.representation: "tore" (2K = channels TORE planes) or "counts" (2 channels: events
  // of each polarity in the last frame period, log(1 + n); the constant-time-frame baseline)
  std::string representation = "tore";
  // run (optional): how `yelan run` uses this model, chosen on validation data.
  //   run.beta: the early-exit threshold it ships with (above 1: stage 1 on every tick).
  //   run.presence {a, b}: P(person) = sigmoid(a * ln(s + 0.001) + b), s the share of the
  //   frame the mask in use covers (fitted by `yelan calibrate`); absent, a fixed guess that
  //   puts P = 0.5 near s = 1% (presence_calibrated false says so). run.presence.tau_s
  //   (optional, default 0): ln(s + 0.001) is first averaged over the ticks, exponentially
  //   with this time constant in seconds (run::PresenceSmoother).
  //   run.depth_scale: the body-height prior's head depth is multiplied by it (fitted by
  //   `yelan calibrate`: a net's skeletons are shorter than the bodies it saw, soft-argmax
  //   pulls joints toward the middle, so the prior alone puts the dancer too far away).
  //   run.depth_forearms (optional, default true): whether the prior counts the forearms
  //   (run::head_depth_from_height; a model's depth_scale is fitted under its choice).
  //   run.depth_tau_s (optional, default 0): the head depth's logarithm is averaged over
  //   the ticks with a person, exponentially with this time constant (run::DepthSmoother).
  //   run.pose_tau_s (optional, default 0): each joint (at unit head depth, before the depth
  //   scales it) is averaged over the ticks with a person, exponentially with this time
  //   constant (run::JointSmoother): stage 2's tick-to-tick jitter against a limb's lag.
  //   run.mask_cut: stage 1's masks are the pixels whose sigmoid exceeds it (default 0.1, a
  //   cut that keeps the dancer for a masked stage 2; `yelan calibrate --choose-mask-cut`
  //   picks the one of best IoU against the true masks).
  //   run.mask_cut_reused (optional, default run.mask_cut): the cut of the future masks that
  //   early exit reuses between stage 1's runs (stage 2's input only; presence and early
  //   exit read every mask at run.mask_cut). A future mask predicted up to 0.3 s before is
  //   a guess at where the limbs will be: a lower cut keeps the events near its edge.
  //   run.mask_grow (optional, default 0): stage 2's masks (stage 1's, fresh or reused, and
  //   the true ones a trainer or `eval --true-mask` uses) grown by this many input pixels in
  //   every direction (a square), so a limb the mask misses by a few pixels still reaches
  //   stage 2; presence, early exit and the IoU read the masks as cut.
  //   run.idle_recheck_s (optional, default 0): while stage 1's last run saw nobody, it runs
  //   again once this many seconds have passed (0: on every tick; at most the future masks'
  //   span, n_masks / 50 s), so an empty room costs a fraction of stage 1 while a dancer who
  //   walks in is seen at most this much later.
  //   run.mask_mirror (optional, default false): at inference stage 1 also runs on the input
  //   mirrored left to right and averages the two's logits (masks mirrored back, scores):
  //   twice stage 1's cost on the ticks it runs, for a net trained with --flip. A number d in
  //   (0, 0.5) instead: only where yelan run is in doubt, on the runs whose current mask alone
  //   gives P(person) in [d, 1 - d] (mask_mirror_doubt; the masks elsewhere are the plain net's).
  //   run.mask_max_age (optional, default 0: none but the n_masks stored): while a dancer is
  //   there, stage 1 runs again once the future mask to reuse would be this many frames (20
  //   ms) old, whatever its score: stage 2's error grows with the age of its mask (about 1 mm
  //   a frame from 4 frames on) while the score falls too little to see it.
  //   run.bf16 (optional, default false): stage 1's convolutions (those of kernel > 1x1 of
  //   its eval-mode ConvBns, and its 2x2 up-sampling) in bf16 on the CPU's AMX tiles where it
  //   has them (Intel Sapphire Rapids and later; kernels/conv_bf16.h), fp32 elsewhere. The
  //   deployed path's (yelan run, eval --run, calibrate, bench run and early-exit); training and
  //   frame-by-frame eval stay fp32.
  //   run.pose_bf16 (optional, default false): stage 2's convolutions likewise in bf16 where
  //   the CPU has AMX (its 3x3 stride-1 ones; the rest, and every CPU without AMX, fp32): on
  //   the default 1.9 against 2.6 ms a tick of stage 2 on one core, its poses the fp32 ones
  //   on validation (+0.0 +- 0.0 mm paired; models/README.md, fifty-eighth session).
  //   run.mask_max_age_bf16 (optional, default run.mask_max_age): the age cap where stage 1
  //   does run in bf16: a stage 1 2.6 times cheaper affords running it more often within the
  //   same pose rate, and the fresher masks fit better.
  //   run.mask_max_age_bf16_winograd (optional, default run.mask_max_age): the same where the
  //   CPU has AVX512-BF16 and no AMX (AMD Zen 4, 5): there run.bf16 runs stage 1's Winograd
  //   GEMMs in bf16 pairs (a quarter cheaper stage 1 on Zen 5), the rest in fp32.
  double run_beta = 0.99;
  bool run_bf16 = false;
  bool run_pose_bf16 = false;
  std::optional<int> mask_max_age_bf16;
  std::optional<int> mask_max_age_bf16_winograd;
  int mask_max_age = 0;  // 0: none
  double mask_cut = 0.1;
  std::optional<double> mask_cut_reused;  // absent: mask_cut
  double reused_mask_cut() const { return mask_cut_reused.value_or(mask_cut); }
  double depth_scale = 1;
  double depth_tau_s = 0;
  double pose_tau_s = 0;
  double idle_recheck_s = 0;
  int mask_grow = 0;
  bool depth_forearms = true;
  bool mask_mirror = false;
  double mask_mirror_doubt = 0;  // 0: none
  static bool mask_mirror_doubt_ok(double d) { return d >= 0 && d < 0.5; }
  double presence_a = 3.0, presence_b = 13.8;
  double presence_tau_s = 0;
  bool presence_calibrated = false;
  std::string json;  // the source text

  int height() const { return sensor_height / downscale; }
  int width() const { return sensor_width / downscale; }
  static int scaled(int base, double mult);
  int unet_width(int level) const { return scaled(64 << level, mask_width); }
  int resnet_c64() const { return scaled(64, pose_width); }
  int resnet_mid() const { return scaled(128, pose_width); }
  int hourglass_lo() const { return scaled(64, pose_width); }
  int hourglass_hi() const { return scaled(128, pose_width); }
};

// Throws ConfigError naming the source and the offending key.
ModelConfig parse_model_config(const std::string& json_text, const std::string& where);
// The config text with run.<key> set to the JSON value `value_json` (other keys kept in
// their order); the result is checked by parse_model_config. Throws ConfigError.
std::string with_run_setting(const std::string& json_text, const std::string& key, const std::string& value_json);

// A name (weights_tools/configs/NAME.json under the source tree) or a path.
ModelConfig load_model_config(const std::string& name_or_path);

}  // namespace yelan
