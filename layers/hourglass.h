// One hourglass stage of one plane (SPEC 5): down_layers = regular(in->lo), regular(lo),
// down(lo->hi), regular(hi), regular(hi); up_layers = regular(hi), regular(hi),
// up(hi->lo, output_padding (H%2==0, W%2==0) of the mid size), regular(lo), regular(lo->J).
// With skip (pose.hourglass_skip, not the paper's): the up block's output plus the second
// down block's (both lo x mid size), so the mid resolution reaches the heatmaps without
// passing through the half-resolution bottleneck; no parameters added.
#pragma once
#include <memory>
#include <vector>

#include "layers/blocks.h"

namespace yelan::layers {

class HourglassStage {
 public:
  HourglassStage(int in, int joints, int lo, int hi, int mid_h, int mid_w, bool skip = false);
  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();
  Act forward(const Act& x);  // -> joints x mid_h x mid_w logits
  void backward(const Act& x, const Act& dy, const Act& dx);

 private:
  std::vector<std::unique_ptr<ResidualBlock>> blocks_;  // 5 down then 5 up
  std::vector<Act> inputs_;                             // each block's input in the last forward
  ActBuf grad_a_, grad_b_;
  bool skip_ = false;
  ActBuf sum_, dsum_;  // the skip's sum (block 8's input) and its gradient
};

// Flat spatial softmax of every map, and DSNT read-out of 3D joints from the xy, zy, xz
// marginals (x, y from xy; z = (zy's width coordinate + xz's height coordinate) / 2).
void flat_softmax_forward(const Act& logits, const Act& probs);
void flat_softmax_backward(const Act& probs, const Act& dprobs, const Act& dlogits);
// joints: n x J x 3 floats (plain)
void dsnt_joints_forward(const Act& xy, const Act& zy, const Act& xz, float* joints);
// Gradients of the three probability maps from dL/djoints (overwrites them).
void dsnt_joints_backward(const float* djoints, const Act& dxy, const Act& dzy, const Act& dxz);

// Depth read off a map (pose.depth_map, not the paper's): each joint's z is its depth map
// averaged under its xy probability map, z_j = sum_px xy_j(px) depth_j(px), instead of the zy
// and xz marginals' coordinates. A convolution places a peak where its evidence lies, so a
// marginal whose axis is depth asks it to move evidence across the image; a depth map asks
// only for a value where the joint is. Overwrites joints[.][2].
void expected_depth_forward(const Act& xy, const Act& depth, float* joints);
// From dL/djoints' z: adds dL/dxy into dxy, overwrites ddepth.
void expected_depth_backward(const float* djoints, const Act& xy, const Act& depth, const Act& dxy, const Act& ddepth);
// The joints of one stage, with or without depth maps (depth null: DSNT alone), and their
// backward: x and y through DSNT; z through DSNT's zy and xz or, with depth maps, through
// expected_depth_backward (ddepth overwritten, dzy and dxz then get no z). Overwrites dxy,
// dzy, dxz as dsnt_joints_backward does.
void stage_joints_forward(const Act& xy, const Act& zy, const Act& xz, const Act* depth, float* joints);
void stage_joints_backward(const float* djoints, const Act& xy, const Act* depth, const Act& dxy, const Act& dzy,
                           const Act& dxz, const Act* ddepth);

}  // namespace yelan::layers
