#include "camera/sim/free_arms.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

// One angle of the curve: Hermite between keys i and i+1, slopes continuous through every
// key and limited as Fritsch and Carlson's monotone cubic limits them (zero at a key that is a
// peak or a trough, at most three times either neighbouring secant), so the curve never
// leaves the range of the keys it joins: an elbow never overshoots past straight.
template <class Get>
double curve(const std::vector<double>& t, Get get, std::size_t i, double s) {
  const std::size_t n = t.size();
  const auto slope = [&](std::size_t k) {
    if (k == 0 || k + 1 >= n) return 0.0;
    const double a = (get(k) - get(k - 1)) / (t[k] - t[k - 1]), b = (get(k + 1) - get(k)) / (t[k + 1] - t[k]);
    if (a * b <= 0) return 0.0;
    const double cr = (get(k + 1) - get(k - 1)) / (t[k + 1] - t[k - 1]);
    const double cap = 3 * std::min(std::abs(a), std::abs(b));
    return std::clamp(cr, -cap, cap);
  };
  const double h = t[i + 1] - t[i], u = (s - t[i]) / h, u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * get(i) + (u3 - 2 * u2 + u) * h * slope(i) + (-2 * u3 + 3 * u2) * get(i + 1) +
         (u3 - u2) * h * slope(i + 1);
}

}  // namespace

FreeArms::FreeArms(const BodyShape& shape, std::uint64_t seed, double duration_s, const ArmRange& range)
    : prop_(body_proportions(shape)), range_(range) {
  if (seed == 0) throw std::invalid_argument("free arms: seed 0 means none; give a nonzero seed");
  if (!(duration_s > 0 && duration_s <= 24 * 3600)) throw std::invalid_argument("free arms: duration must be in (0 s, 24 h]");
  Rng r(seed, 0xf4eea4315ull);
  const auto draw = [&](const double* lohi) { return r.uniform(lohi[0], lohi[1]) * kDeg; };
  const auto pose = [&] {
    return ArmAngles{draw(range_.elevation), draw(range_.plane), draw(range_.twist), draw(range_.flex), draw(range_.wrist)};
  };
  // Both arms share the keys' times; a third of the keys are symmetric (both arms the same
  // angles, which the two sides' mirrored axes make a mirror image), as dancers often move.
  for (double t = 0;; t += r.uniform(0.3, 1.2)) {
    const ArmAngles right = pose(), left = r.uniform() < 0.35 ? right : pose();
    times_.push_back(t);
    keys_[0].push_back(right);
    keys_[1].push_back(left);
    if (t > duration_s + 1) break;
  }
}

ArmAngles FreeArms::angles(int side, double t_s) const {
  if (side != 0 && side != 1) throw std::invalid_argument("free arms: side must be 0 (right) or 1 (left)");
  const std::vector<ArmAngles>& k = keys_[std::size_t(side)];
  t_s = std::clamp(t_s, times_.front(), times_.back());
  const std::size_t after = std::size_t(std::upper_bound(times_.begin(), times_.end(), t_s) - times_.begin());
  const std::size_t i = std::min(after == 0 ? 0 : after - 1, times_.size() - 2);
  const auto at = [&](double ArmAngles::*field) {
    return curve(times_, [&](std::size_t j) { return k[j].*field; }, i, t_s);
  };
  return ArmAngles{at(&ArmAngles::elevation), at(&ArmAngles::plane), at(&ArmAngles::twist), at(&ArmAngles::flex),
                   at(&ArmAngles::wrist)};
}

BodyPose FreeArms::apply(const BodyPose& body, double t_s) const {
  const Vec3 up = (body.p[kNeck] - body.p[kChest]).normalized();
  Vec3 left = body.p[kShoulderL] - body.p[kShoulderR];
  left = (left - left.dot(up) * up).normalized();
  Eigen::Matrix3d chest;  // the procedural dance's chest frame: x the dancer's left, y backwards, z up
  chest.col(0) = left;
  chest.col(1) = up.cross(left);
  chest.col(2) = up;
  const auto rot = [](double a, const Vec3& axis) { return Eigen::AngleAxisd(a, axis).toRotationMatrix(); };
  BodyPose out = body;
  for (int side = 0; side < 2; ++side) {
    const ArmAngles a = angles(side, t_s);
    const double sg = side ? 1 : -1;
    const Eigen::Matrix3d ra = chest * rot(-a.plane * sg, Vec3::UnitZ()) * rot(-a.elevation * sg, Vec3::UnitY()) *
                               rot(a.twist * sg, Vec3::UnitZ());
    const Vec3 u = -ra.col(2), bend = -ra.col(1);  // along the upper arm; the way the elbow folds
    const double wf = a.flex + a.wrist;
    Vec3& elbow = out.p[kElbowR + side];
    Vec3& wrist = out.p[kWristR + side];
    elbow = body.p[kShoulderR + side] + prop_.upper_arm * u;
    wrist = elbow + prop_.forearm * (std::cos(a.flex) * u + std::sin(a.flex) * bend);
    out.p[kHandTipR + side] = wrist + prop_.hand * (std::cos(wf) * u + std::sin(wf) * bend);
  }
  return out;
}

}  // namespace yelan::camera::sim
