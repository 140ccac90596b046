#include "engine/train/floors.h"

#include <cmath>

#include "camera/sim/dataset.h"
#include "camera/sim/rng.h"
#include "camera/sim/simulator.h"

namespace yelan::train {

namespace sim = camera::sim;

namespace {

std::array<double, 3> hip_centre(const Pose13& p) {
  return {(p[5][0] + p[6][0]) / 2, (p[5][1] + p[6][1]) / 2, (p[5][2] + p[6][2]) / 2};
}

Pose13 at_hip(const Pose13& rel, const std::array<double, 3>& hip) {
  Pose13 out;
  for (int j = 0; j < kJoints; ++j)
    for (int c = 0; c < 3; ++c) out[j][c] = rel[j][c] + hip[c];
  return out;
}

double mean_error(const Pose13& a, const Pose13& b, const std::array<std::uint8_t, kJoints>& valid) {
  double s = 0;
  int n = 0;
  for (int j = 0; j < kJoints; ++j) {
    if (!valid[j]) continue;
    s += std::sqrt((a[j][0] - b[j][0]) * (a[j][0] - b[j][0]) + (a[j][1] - b[j][1]) * (a[j][1] - b[j][1]) +
                   (a[j][2] - b[j][2]) * (a[j][2] - b[j][2]));
    ++n;
  }
  return n ? s / n : 0;
}

struct Mean {
  Pose13 sum{};
  std::array<double, kJoints> n{};
  void add(int j, const std::array<double, 3>& v) {
    for (int c = 0; c < 3; ++c) sum[j][c] += v[c];
    ++n[j];
  }
  Pose13 get() const {
    Pose13 out{};
    for (int j = 0; j < kJoints; ++j)
      for (int c = 0; c < 3; ++c) out[j][c] = n[j] ? sum[j][c] / n[j] : 0;
    return out;
  }
};

}  // namespace

FloorStats training_floor_stats(int members, int times, bool framed) {
  Mean norm, rel;
  std::map<std::string, Mean> view;
  for (int i = 0; i < members; ++i) {
    const sim::SimSpec spec = sim::dataset_member("train", i, 1, 5.0, false, framed);
    const sim::Simulator s(spec);
    const sim::CameraModel& cam = s.camera();
    const Intrinsics k{cam.fx, cam.fy, cam.cx, cam.cy, cam.width, cam.height};
    Mean& v = view[sim::view_name(spec.scene.view)];
    for (int t = 0; t < times; ++t) {
      const sim::Label l = s.label_at(spec.duration_s * (t + 0.5) / times);
      Pose13 p;
      for (int j = 0; j < kJoints; ++j) p[j] = {l.joints_mm[j].x(), l.joints_mm[j].y(), l.joints_mm[j].z()};
      const double zr = p[0][2];
      const auto hip = hip_centre(p);
      for (int j = 0; j < kJoints; ++j) {
        if (!l.valid[j] || !(zr > 1)) continue;
        norm.add(j, normalise_joint(p[j], k, zr));
        const std::array<double, 3> r{p[j][0] - hip[0], p[j][1] - hip[1], p[j][2] - hip[2]};
        rel.add(j, r);
        v.add(j, r);
      }
    }
  }
  FloorStats out;
  out.mean_norm = norm.get();
  out.mean_rel = rel.get();
  for (const auto& [name, m] : view) out.view_rel[name] = m.get();
  return out;
}

void Floors::add(const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid, const Intrinsics& k, double z_ref,
                 const std::string& view) {
  Pose13 c;
  for (int j = 0; j < kJoints; ++j) c[j] = denormalise_joint(stats_.mean_norm[j], k, z_ref);
  constant_.add(c, truth, valid);
  const auto hip = hip_centre(truth);
  at_hip_.add(at_hip(stats_.mean_rel, hip), truth, valid);
  per_view_.add(per_view_prediction(truth, view), truth, valid);
}

Pose13 Floors::per_view_prediction(const Pose13& truth, const std::string& view) const {
  const auto it = stats_.view_rel.find(view);
  return at_hip(it != stats_.view_rel.end() ? it->second : stats_.mean_rel, hip_centre(truth));
}

std::map<std::string, PoseScores> Floors::scores() const {
  return {{"constant", constant_.scores()},
          {"mean_pose_at_hip", at_hip_.scores()},
          {"per_view_mean_pose_at_hip", per_view_.scores()}};
}

void SwapShare::add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid,
                    const std::string& view) {
  auto& [better, frames] = n_[view];
  better += mean_error(swap_left_right(pred), truth, valid) < mean_error(pred, truth, valid);
  ++frames;
}

std::map<std::string, double> SwapShare::by_view() const {
  std::map<std::string, double> out;
  for (const auto& [v, n] : n_) out[v] = n.second ? double(n.first) / double(n.second) : 0;
  return out;
}

}  // namespace yelan::train
