#include "engine/train/metrics.h"

#include <cmath>

namespace yelan::train {

namespace {
double norm3(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}
// Hip centre: the mean of hipR (5) and hipL (6).
std::array<double, 3> root(const Pose13& p) {
  return {(p[5][0] + p[6][0]) / 2, (p[5][1] + p[6][1]) / 2, (p[5][2] + p[6][2]) / 2};
}
double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / double(v.size());
}
}  // namespace

double pck(const std::vector<double>& dist, double threshold_mm) {
  if (dist.empty()) return 0;
  std::size_t n = 0;
  for (double d : dist) n += d <= threshold_mm;
  return double(n) / double(dist.size());
}

double auc(const std::vector<double>& dist) {
  double s = 0;
  for (int i = 0; i < 30; ++i) s += pck(dist, 500.0 * i / 29);
  return s / 30;
}

void PoseMetrics::add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid) {
  const auto rp = root(pred), rt = root(truth);
  bool any = false;
  for (int j = 0; j < kJoints; ++j) {
    if (!valid[j]) continue;
    any = true;
    const double d = norm3(pred[j], truth[j]);
    dist_.push_back(d);
    if (valid[5] && valid[6]) {  // the hip centre needs both hips
      std::array<double, 3> a, b;
      for (int k = 0; k < 3; ++k) a[k] = pred[j][k] - rp[k], b[k] = truth[j][k] - rt[k];
      dist_root_.push_back(norm3(a, b));
    }
    joint_sum_[j] += d;
    ++joint_n_[j];
  }
  frames_ += any;
}

void PoseMetrics::merge(const PoseMetrics& o) {
  dist_.insert(dist_.end(), o.dist_.begin(), o.dist_.end());
  dist_root_.insert(dist_root_.end(), o.dist_root_.begin(), o.dist_root_.end());
  for (int j = 0; j < kJoints; ++j) joint_sum_[j] += o.joint_sum_[j], joint_n_[j] += o.joint_n_[j];
  frames_ += o.frames_;
}

PoseScores PoseMetrics::scores() const {
  PoseScores s;
  s.mpjpe_mm = mean(dist_);
  s.pck150 = pck(dist_, 150);
  s.auc = auc(dist_);
  s.mpjpe_root_mm = mean(dist_root_);
  s.pck150_root = pck(dist_root_, 150);
  s.auc_root = auc(dist_root_);
  s.frames = frames_;
  s.joints = dist_.size();
  for (int j = 0; j < kJoints; ++j) {
    s.mpjpe_per_joint[j] = joint_n_[j] ? joint_sum_[j] / double(joint_n_[j]) : 0;
    s.joint_frames[j] = joint_n_[j];
  }
  return s;
}

void ErrorSplit::add(const Pose13& pred, const Pose13& truth, const std::array<std::uint8_t, kJoints>& valid,
                     const Intrinsics& k) {
  const auto project = [&](const std::array<double, 3>& p) {
    return std::array<double, 2>{k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy};
  };
  const bool hips = valid[5] && valid[6];
  const double hip_shift = hips ? root(pred)[2] - root(truth)[2] : 0.0;
  for (int j = 0; j < kJoints; ++j) {
    const auto& a = pred[std::size_t(j)];
    const auto& b = truth[std::size_t(j)];
    // A joint at or behind the camera has no image position.
    if (!valid[std::size_t(j)] || a[2] <= 0 || b[2] <= 0) continue;
    const auto pa = project(a), pb = project(b);
    px_[std::size_t(j)] += std::hypot(pa[0] - pb[0], pa[1] - pb[1]);
    dz_[std::size_t(j)] += std::abs(a[2] - b[2]);
    dz_signed_[std::size_t(j)] += a[2] - b[2];
    ++n_[std::size_t(j)];
    if (hips) {
      dz_root_[std::size_t(j)] += std::abs(a[2] - b[2] - hip_shift);
      ++n_root_[std::size_t(j)];
    }
  }
}

ErrorSplitScores ErrorSplit::scores() const {
  ErrorSplitScores s;
  double px = 0, dz = 0, dz_root = 0;
  std::uint64_t n = 0, n_root = 0;
  for (std::size_t j = 0; j < std::size_t(kJoints); ++j) {
    s.n[j] = n_[j];
    s.n_root[j] = n_root_[j];
    if (n_root_[j]) s.depth_root_mm[j] = dz_root_[j] / double(n_root_[j]);
    dz_root += dz_root_[j];
    n_root += n_root_[j];
    if (n_[j] == 0) continue;
    s.image_px[j] = px_[j] / double(n_[j]);
    s.depth_mm[j] = dz_[j] / double(n_[j]);
    s.depth_bias_mm[j] = dz_signed_[j] / double(n_[j]);
    px += px_[j];
    dz += dz_[j];
    n += n_[j];
  }
  if (n) {
    s.mean_image_px = px / double(n);
    s.mean_depth_mm = dz / double(n);
  }
  if (n_root) s.mean_depth_root_mm = dz_root / double(n_root);
  return s;
}

}  // namespace yelan::train
