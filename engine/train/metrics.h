// Pose metrics (SPEC section 7): MPJPE (mm, mean Euclidean distance over valid joints),
// PCK@150 mm, AUC = mean PCK over 30 thresholds linspace(0, 500, 30) mm; under the paper
// protocol (as predicted) and root-aligned (both poses shifted so the hip centre is the
// origin); per joint and per condition. Accumulates frame by frame.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "engine/joints.h"
#include "engine/train/pose_norm.h"

namespace yelan::train {

inline constexpr int kJoints = 13;
using Pose13 = std::array<std::array<double, 3>, kJoints>;

// Per-joint values (a pose, validity flags) with left and right exchanged.
template <class T>
std::array<T, kJoints> swap_left_right(const std::array<T, kJoints>& p) {
  std::array<T, kJoints> out;
  for (int j = 0; j < kJoints; ++j) out[std::size_t(j)] = p[std::size_t(mirror_joint(j))];
  return out;
}

struct PoseScores {
  double mpjpe_mm = 0, pck150 = 0, auc = 0, mpjpe_root_mm = 0, pck150_root = 0, auc_root = 0;
  std::uint64_t frames = 0, joints = 0;
  std::array<double, kJoints> mpjpe_per_joint{};
  std::array<std::uint64_t, kJoints> joint_frames{};  // 0: never visible (report n/a, not 0 mm)
};

class PoseMetrics {
 public:
  // valid: which joints count; a frame with no valid joint is skipped.
  void add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid);
  PoseScores scores() const;
  void merge(const PoseMetrics& other);

 private:
  std::vector<double> dist_, dist_root_;  // one per valid joint
  std::array<double, kJoints> joint_sum_{};
  std::array<std::uint64_t, kJoints> joint_n_{};
  std::uint64_t frames_ = 0;
};

// Where the error lies: per joint, the distance in the image (sensor pixels, both poses
// projected with the camera's intrinsics) and along the optical axis (|dz|, mm). A net that
// places joints well in the image but not in depth needs depth cues; one that misses in the
// image does not see the limbs. Depth also signed (depth_bias_mm: mean of predicted minus true
// z; a net whose depths shrink towards the head's shows it) and after aligning the hip
// centres' depths (depth_root_mm; frames with both hips valid): a body placed at the wrong
// depth as a whole is told apart from limbs at the wrong depth within it.
struct ErrorSplitScores {
  std::array<double, kJoints> image_px{}, depth_mm{}, depth_bias_mm{}, depth_root_mm{};
  std::array<std::uint64_t, kJoints> n{}, n_root{};
  double mean_image_px = 0, mean_depth_mm = 0, mean_depth_root_mm = 0;
};

class ErrorSplit {
 public:
  // k: the camera whose pixels the image-plane error is counted in.
  void add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid, const Intrinsics& k);
  ErrorSplitScores scores() const;

 private:
  std::array<double, kJoints> px_{}, dz_{}, dz_signed_{}, dz_root_{};
  std::array<std::uint64_t, kJoints> n_{}, n_root_{};
};

// The 30 AUC thresholds: 0, 500/29, ..., 500 mm.
double pck(const std::vector<double>& dist, double threshold_mm);
double auc(const std::vector<double>& dist);

}  // namespace yelan::train
