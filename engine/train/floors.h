// What a prediction is measured against: trivial predictors scored on the same frames as the
// model (a model that does not beat them clearly has learned nothing), and the share of
// frames where swapping the predicted left and right joints would lower the error (a model
// that cannot tell a front from a back).
//   constant:                  the training targets' mean normalised pose, denormalised with
//                              the true head depth (what a net that ignores its input outputs)
//   mean_pose_at_hip:          the training split's mean hip-relative pose at the true hip
//   per_view_mean_pose_at_hip: the same mean per camera view (knows which way the dancer faces)
// Means come from the training split of the dataset (camera/sim/dataset.h) with its labels
// drawn at many times without rendering.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>

#include "engine/train/metrics.h"
#include "engine/train/pose_norm.h"

namespace yelan::train {

struct FloorStats {
  Pose13 mean_norm{};                   // normalised units
  Pose13 mean_rel{};                    // mm, camera frame, relative to the hip centre
  std::map<std::string, Pose13> view_rel;  // by view name
};

// Means over `members` training-split dataset members (seed 1, the shipped dataset's) at
// `times` instants each; framed: with the dancer framed (SimSpec::frame_dancer), as the
// frames scored are.
FloorStats training_floor_stats(int members = 240, int times = 25, bool framed = true);

class Floors {
 public:
  explicit Floors(const FloorStats& stats) : stats_(stats) {}
  void add(const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid, const Intrinsics& k, double z_ref,
           const std::string& view);
  std::map<std::string, PoseScores> scores() const;
  // What per_view_mean_pose_at_hip predicts for this frame.
  Pose13 per_view_prediction(const Pose13& truth, const std::string& view) const;

 private:
  FloorStats stats_;
  PoseMetrics constant_, at_hip_, per_view_;
};

// Per view: the share of frames where the prediction with left and right swapped is closer.
class SwapShare {
 public:
  void add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid, const std::string& view);
  std::map<std::string, double> by_view() const;

 private:
  std::map<std::string, std::pair<std::uint64_t, std::uint64_t>> n_;  // view -> (better swapped, frames)
};

}  // namespace yelan::train
