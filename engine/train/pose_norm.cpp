#include "engine/train/pose_norm.h"

#include <algorithm>
#include <cmath>

namespace yelan::train {

namespace {
struct DepthScale {
  double s, r;
};
DepthScale depth_scale(const Intrinsics& k, double z_ref) {
  const double s = z_ref * std::max(k.width / k.fx, k.height / k.fy);
  return {s, std::sqrt(z_ref * z_ref + s * s)};
}
}  // namespace

std::array<double, 3> normalise_joint(const std::array<double, 3>& p, const Intrinsics& k, double z_ref) {
  const double u = k.fx * p[0] / p[2] + k.cx, v = k.fy * p[1] / p[2] + k.cy;
  const DepthScale d = depth_scale(k, z_ref);
  return {(u - k.width / 2.0) / (k.width / 2.0), (v - k.height / 2.0) / (k.height / 2.0),
          (d.r + z_ref) / d.s * (1 - z_ref / p[2])};
}

std::array<double, 3> denormalise_joint(const std::array<double, 3>& n, const Intrinsics& k, double z_ref) {
  const DepthScale d = depth_scale(k, z_ref);
  const double z = z_ref / (1 - n[2] * d.s / (d.r + z_ref));
  const double u = n[0] * (k.width / 2.0) + k.width / 2.0, v = n[1] * (k.height / 2.0) + k.height / 2.0;
  return {(u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z};
}

}  // namespace yelan::train
