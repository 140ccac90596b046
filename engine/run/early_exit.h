// Choosing the early-exit threshold beta on validation recordings: the deployed pipeline
// runs over each dancer recording once per beta, and at every tick the mask in use (fresh or
// a stored future mask) is compared with the recording's true mask. The beta a model ships
// with (its config's run.beta) is the one that runs stage 1 least while keeping the mask
// IoU within a tolerance of stage 1 on every tick.
#pragma once
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace yelan::run {

struct BetaPoint {
  double beta = 0;
  double stage1_share = 0;  // of the ticks with events
  double iou = 0;           // mask in use against the true mask, pooled over ticks
  std::uint64_t ticks = 0;
  // Where stage 1 ran and the future it predicted is within the recording: each mask's score
  // against its true quality, 1 - mean |mask - true mask| (what the score is trained to say).
  double score_quality_correlation = 0;  // Pearson
  double score_quality_mae = 0;          // mean |score - quality|
  std::uint64_t scored_masks = 0;
};

// One point per beta (in the order given), over at most `seconds` of each recording after
// `skip_s` (the TORE filling).
// mask_cut: stage 1's cut instead of the model's run.mask_cut.
std::vector<BetaPoint> sweep_beta(const std::string& weights, const std::vector<std::string>& recordings,
                                  const std::vector<double>& betas, double rate_hz, double seconds, double skip_s,
                                  std::ostream& progress, std::optional<double> mask_cut = std::nullopt);

// Stage 1's mask IoU at each cut (sigmoid > cut, in the order given) with stage 1 on every
// tick, the same ticks and pooling as sweep_beta at beta 1.01 with that cut, in one pass
// over the recordings: every cut is applied to the same logits.
std::vector<double> sweep_mask_cuts(const std::string& weights, const std::vector<std::string>& recordings,
                                    const std::vector<double>& cuts, double rate_hz, double seconds, double skip_s,
                                    std::ostream& progress);

// The point with the smallest stage-1 share whose IoU is at least the best IoU of the sweep
// minus `tolerance` (ties: the larger beta).
BetaPoint choose_beta(const std::vector<BetaPoint>& points, double tolerance);

}  // namespace yelan::run
