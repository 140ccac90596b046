#include "camera/sim/body.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {
namespace {

constexpr double kGravity = 9810.0;       // mm/s^2
constexpr double kMaxSubstep = 1e-3;      // s: keeps h * sqrt(k) below 0.013 for every spring
constexpr double kRestartGap = 0.25;      // s: a longer step is a cut, not motion
constexpr double kMaxFollowSpeed = 4000;  // mm/s, see damp_against()
constexpr double kMaxYawRate = 40;        // rad/s, beyond any pirouette
constexpr std::uint64_t kStreamSprings = 0xb0d7'0001, kStreamPrints = 0xb0d7'0002;

Vec3 safe_normalized(const Vec3& v, const Vec3& fallback) {
  const double n = v.norm();
  return n > 1e-9 ? Vec3(v / n) : fallback;
}

Vec3 any_perpendicular(const Vec3& unit) {
  const Vec3 ref = std::abs(unit.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return unit.cross(ref).normalized();
}

// Unit vector along `hint` with its component along `unit` removed.
Vec3 perpendicular_part(const Vec3& hint, const Vec3& unit) {
  const Vec3 p = hint - unit * unit.dot(hint);
  const double n = p.norm();
  return n > 1e-6 * (1 + hint.norm()) ? Vec3(p / n) : any_perpendicular(unit);
}

// Spring-damper towards a moving attachment. The damping acts on the velocity relative to
// the attachment so cloth carried along at constant speed does not trail behind; that
// speed is capped so a teleported pose (a cut in the motion) makes the cloth swing over
// smoothly instead of being kicked.
Vec3 damp_against(const Vec3& attachment_velocity) {
  const double s = attachment_velocity.norm();
  return s > kMaxFollowSpeed ? Vec3(attachment_velocity * (kMaxFollowSpeed / s))
                             : attachment_velocity;
}

Material dressed(const Material& m, const Vec3& origin, const Vec3& u, const Vec3& v,
                 std::uint32_t print_seed) {
  Material out = m;
  out.origin = origin;
  out.u_axis = u;
  out.v_axis = v;
  out.print_seed = m.print_seed ^ print_seed;
  return out;
}

}  // namespace

Dresser::Dresser(const Character& character, std::uint64_t seed)
    : character_(character), seed_(seed) {
  const double H = character.shape.height_mm, g = character.shape.girth;
  // Far wider than the cast (1500..1950 mm, 0.8..1.4) so configs can explore, but no
  // nonsense: a NaN or a 10 m giant would only make garbage geometry downstream.
  if (!(H >= 500 && H <= 3000) || !(g >= 0.3 && g <= 3))
    throw std::invalid_argument("character '" + character.name + "': height_mm " +
                                std::to_string(H) + " (500..3000) or girth " +
                                std::to_string(g) + " (0.3..3) out of range");
  const bool f = character.shape.female;
  const double limb = g * (f ? 0.92 : 1.0);
  Dims& d = dims_;
  // Proportions of H for an average adult (girth 1); girth widens flesh, not bones.
  d.head_side = 0.044 * H * (0.9 + 0.1 * g);
  d.head_depth = 0.056 * H * (0.9 + 0.1 * g);
  d.jaw_r = 0.020 * H * (0.85 + 0.15 * g);
  d.neck_r = (f ? 0.030 : 0.034) * H * (0.75 + 0.25 * g);
  d.chest_lat_per_shoulder = (f ? 0.34 : 0.36) * (0.75 + 0.25 * g);
  d.chest_depth = 0.065 * H * g;
  d.belly_lat = (f ? 0.074 : 0.082) * H * (0.55 + 0.45 * g);
  d.belly_depth = (f ? 0.056 : 0.058) * H * g;
  d.pelvis_lat_extra = (f ? 0.052 : 0.045) * H * (0.6 + 0.4 * g);
  d.pelvis_depth = (f ? 0.066 : 0.060) * H * g;
  d.pelvis_up = 0.070 * H;
  d.upper_arm_r0 = 0.029 * H * limb;
  d.upper_arm_r1 = 0.023 * H * limb;
  d.forearm_r0 = 0.022 * H * limb;
  d.forearm_r1 = 0.016 * H * limb;
  d.hand_r0 = 0.016 * H * (f ? 0.9 : 1.0) * (0.8 + 0.2 * g);
  d.hand_r1 = 0.012 * H * (f ? 0.9 : 1.0) * (0.8 + 0.2 * g);
  d.thigh_r0 = 0.050 * H * g;
  d.thigh_r1 = 0.031 * H * limb;
  d.shin_r0 = 0.031 * H * limb;
  d.shin_r1 = 0.019 * H * limb;
  d.foot_r0 = 0.022 * H * (0.85 + 0.15 * g);
  d.foot_r1 = 0.016 * H * (0.85 + 0.15 * g);

  Rng rng(seed, kStreamSprings);
  const double hem_scale = rng.uniform(0.9, 1.1), hair_scale = rng.uniform(0.9, 1.1);

  // Loose cloth: attachment height on the hips' axis, radius there, slant length to the
  // hem and the hem radius at rest.
  Hem& hem = hem_;
  // Half the hip-joint spacing (as motion.cpp's proportions have it).
  const double hip_half_width = (f ? 0.060 : 0.055) * H;
  const double pelvis_lat = hip_half_width + d.pelvis_lat_extra;
  const double hip_ra = 1.05 * std::max(pelvis_lat, hip_half_width + d.thigh_r0);
  double axis_length = 0, rb = 0, k = 60, zeta = 0.8, max_flare = 1.0;
  switch (character.clothing) {
    case Clothing::tight: break;
    case Clothing::loose_shirt:
      hem.top_offset = 0.10 * H;
      hem.ra = 1.12 * d.belly_lat;
      axis_length = 0.15 * H;
      rb = 1.10 * pelvis_lat;
      k = 150;
      zeta = 0.7;
      max_flare = 0.35;
      break;
    case Clothing::long_coat:
      hem.ra = hip_ra;
      axis_length = 0.29 * H;
      rb = 1.25 * hip_ra;
      max_flare = 0.5;  // heavy cloth
      break;
    case Clothing::dress:
      hem.ra = hip_ra;
      axis_length = 0.30 * H;
      rb = 1.30 * hip_ra;
      break;
    case Clothing::skirt:
      hem.ra = hip_ra;
      axis_length = 0.20 * H;
      rb = 1.20 * hip_ra;
      break;
  }
  hem.active = axis_length > 0;
  if (hem.active) {
    rb = std::max(rb, hem.ra);
    hem.length = std::hypot(axis_length, rb - hem.ra);
    hem.rest_angle = std::atan2(rb - hem.ra, axis_length);
    hem.max_angle = std::max(max_flare, hem.rest_angle);
    hem.k = k * hem_scale;
    hem.c = 2 * zeta * std::sqrt(hem.k);
  }
  hair_active_ = character.hair == Hair::long_hair;
  hair_segment_ = 0.05 * H;
  hair_k_ = 120 * hair_scale;
  hair_c_ = 2 * 0.5 * std::sqrt(hair_k_);
  for (int i = 0; i < kMaxPrimitives; ++i)
    print_seeds_[i] = std::uint32_t(hash64(seed, kStreamPrints, std::uint64_t(i)));
}

void Dresser::compute_axes() {
  const auto& p = pose_.p;
  auto trunk = [](const Vec3& lat_hint, const Vec3& up_hint, const Axes& previous) {
    Axes a;
    a.up = safe_normalized(up_hint, previous.up);
    a.lat = perpendicular_part(lat_hint.squaredNorm() > 1e-12 ? lat_hint : previous.lat, a.up);
    a.fwd = a.lat.cross(a.up);  // left x up = forward (rest: x cross z = -y)
    return a;
  };
  torso_ = trunk(p[kShoulderL] - p[kShoulderR], p[kNeck] - p[kChest], torso_);
  hips_ = trunk(p[kHipL] - p[kHipR], p[kChest] - p[kPelvis], hips_);
  const Vec3 up_vec = p[kHeadTop] - p[kHead];
  head_up_ = std::max(up_vec.norm(), 0.5 * dims_.head_side);
  head_.up = safe_normalized(up_vec, head_.up);
  head_.fwd = perpendicular_part(p[kNose] - p[kHead], head_.up);
  head_.lat = head_.up.cross(head_.fwd);
}

void Dresser::hem_targets(Vec3& centre, double& radius, double yaw_rate) const {
  const Vec3 top = pose_.p[kPelvis] + hips_.up * hem_.top_offset;
  // Cloth hangs mostly under gravity, partly along the body.
  const Vec3 down = safe_normalized(-0.6 * Vec3::UnitZ() - 0.4 * hips_.up, -Vec3::UnitZ());
  // A ring of cloth spun at w stands at the cone angle where tan(angle) = w^2 r / g.
  double angle = hem_.rest_angle;
  const double w2 = yaw_rate * yaw_rate;
  for (int i = 0; i < 4 && w2 > 0; ++i) {
    const double r = hem_.ra + hem_.length * std::sin(angle);
    angle = std::clamp(std::atan(w2 * r / kGravity), hem_.rest_angle, hem_.max_angle);
  }
  const double depth = hem_.length * std::cos(angle);
  centre = top + down * depth;
  radius = hem_.ra + hem_.length * std::sin(angle);

  // The legs push the cloth: where both cross the hem's level, the ring moves over their
  // midpoint (at most half its length) and opens wide enough to hold them.
  const Dims& d = dims_;
  Vec3 leg[2];
  double leg_r[2];
  for (int side = 0; side < 2; ++side) {
    const Vec3 chain[3] = {pose_.p[kHipR + side], pose_.p[kKneeR + side], pose_.p[kAnkleR + side]};
    const double r[3] = {d.thigh_r0, d.thigh_r1, d.shin_r1};
    bool found = false;
    for (int s = 0; s < 2 && !found; ++s) {
      const double b0 = (chain[s] - top).dot(down), b1 = (chain[s + 1] - top).dot(down);
      if ((b0 - depth) * (b1 - depth) > 0 || b0 == b1) continue;
      const double f = (depth - b0) / (b1 - b0);
      leg[side] = chain[s] + f * (chain[s + 1] - chain[s]);
      leg_r[side] = r[s] + f * (r[s + 1] - r[s]);
      found = true;
    }
    if (!found) return;  // a leg lifted above the hem does not hold the cloth open
  }
  Vec3 shift = 0.5 * (leg[0] + leg[1]) - centre;
  shift -= down * shift.dot(down);
  const double most = 0.5 * hem_.length, n = shift.norm();
  if (n > most) shift *= most / n;
  centre += shift;
  for (int side = 0; side < 2; ++side) {
    Vec3 off = leg[side] - centre;
    off -= down * off.dot(down);
    radius = std::max(radius, off.norm() + leg_r[side] + 8.0);
  }
  radius = std::min(radius, hem_.ra + hem_.length);
}

Vec3 Dresser::hair_anchor() const {
  return pose_.p[kHead] - head_.fwd * (0.6 * dims_.head_depth) + head_.up * (0.1 * head_up_);
}

Vec3 Dresser::hair_direction() const {
  return safe_normalized(-0.5 * head_.up - 0.2 * head_.fwd - 0.5 * Vec3::UnitZ(),
                         -Vec3::UnitZ());
}

void Dresser::reset_at_rest() {
  yaw_rate_ = 0;
  if (hem_.active) {
    hem_targets(hem_.target, hem_.r_target, 0);
    hem_.x = hem_.target;
    hem_.r = hem_.r_target;
    hem_.v.setZero();
    hem_.vr = 0;
  }
  hair_x_[0] = hair_anchor();
  const Vec3 dir = hair_direction();
  for (int i = 0; i < kHairNodes; ++i) {
    if (i > 0) hair_x_[i] = hair_x_[i - 1] + dir * hair_segment_;
    hair_v_[i].setZero();
  }
}

void Dresser::update(const BodyPose& pose, double t_s) {
  // A non-finite input would poison the spring state for good, so refuse it.
  if (!std::isfinite(t_s)) throw std::invalid_argument("Dresser::update: time is not finite");
  for (int i = 0; i < kBodyPointCount; ++i)
    if (!pose.p[i].allFinite())
      throw std::invalid_argument("Dresser::update: body point " + std::to_string(i) +
                                  " is not finite");
  const double dt = t_s - t_;
  if (!started_ || !(dt >= 0) || dt > kRestartGap) {
    pose_ = pose;
    compute_axes();
    reset_at_rest();
    started_ = true;
    t_ = t_s;
    return;
  }
  const Vec3 old_lat = hips_.lat;
  const Vec3 old_hem_target = hem_.target, old_anchor = hair_anchor();
  const Vec3 old_dir = hair_direction();
  const double old_r_target = hem_.r_target;
  pose_ = pose;
  compute_axes();
  t_ = t_s;
  if (dt <= 0) {
    if (hem_.active) hem_targets(hem_.target, hem_.r_target, yaw_rate_);
    return;
  }

  // Yaw rate of the hips, low-passed over ~20 ms so pose noise does not flare the skirt.
  const double dyaw = std::atan2(old_lat.cross(hips_.lat).z(), old_lat.dot(hips_.lat));
  const double raw = std::clamp(dyaw / dt, -kMaxYawRate, kMaxYawRate);
  yaw_rate_ += (raw - yaw_rate_) * std::min(1.0, dt / 0.02);

  const int n = std::max(1, int(std::ceil(dt / kMaxSubstep - 1e-9)));
  const double h = dt / n;
  if (hem_.active) {
    hem_targets(hem_.target, hem_.r_target, yaw_rate_);
    const Vec3 follow = damp_against((hem_.target - old_hem_target) / dt);
    const Vec3 top = pose_.p[kPelvis] + hips_.up * hem_.top_offset;
    const double max_reach = 1.3 * hem_.length;
    for (int i = 1; i <= n; ++i) {
      const double s = double(i) / n;
      const Vec3 target = old_hem_target + (hem_.target - old_hem_target) * s;
      const double r_target = old_r_target + (hem_.r_target - old_r_target) * s;
      hem_.v += h * (hem_.k * (target - hem_.x) - hem_.c * (hem_.v - follow));
      hem_.x += h * hem_.v;
      hem_.vr += h * (hem_.k * (r_target - hem_.r) - hem_.c * hem_.vr);
      hem_.r += h * hem_.vr;
    }
    // Cloth does not stretch: keep the hem within reach of its waistband.
    const Vec3 from_top = hem_.x - top;
    const double reach = from_top.norm();
    if (reach > max_reach) {
      const Vec3 unit = from_top / reach;
      hem_.x = top + unit * max_reach;
      const double outward = hem_.v.dot(unit);
      if (outward > 0) hem_.v -= unit * outward;
    }
    hem_.r = std::clamp(hem_.r, 0.5 * hem_.ra, hem_.ra + hem_.length);
  }
  if (hair_active_) {
    const Vec3 anchor = hair_anchor(), dir = hair_direction();
    const Vec3 anchor_follow = damp_against((anchor - old_anchor) / dt);
    for (int i = 1; i <= n; ++i) {
      const double s = double(i) / n;
      const Vec3 step_dir = safe_normalized(old_dir + (dir - old_dir) * s, dir);
      hair_x_[0] = old_anchor + (anchor - old_anchor) * s;
      hair_v_[0] = anchor_follow;
      for (int j = 1; j < kHairNodes; ++j) {
        const Vec3 target = hair_x_[j - 1] + step_dir * hair_segment_;
        hair_v_[j] += h * (hair_k_ * (target - hair_x_[j]) -
                           hair_c_ * (hair_v_[j] - damp_against(hair_v_[j - 1])));
        hair_x_[j] += h * hair_v_[j];
        // Hair stretches little: pull a node back within 1.2 segments of its parent.
        const Vec3 link = hair_x_[j] - hair_x_[j - 1];
        const double len = link.norm();
        if (len > 1.2 * hair_segment_) {
          const Vec3 unit = link / len;
          hair_x_[j] = hair_x_[j - 1] + unit * (1.2 * hair_segment_);
          const double outward = (hair_v_[j] - hair_v_[j - 1]).dot(unit);
          if (outward > 0) hair_v_[j] -= unit * outward;
        }
      }
    }
  }
}

void Dresser::primitives(std::vector<Primitive>& out) const {
  const auto& p = pose_.p;
  const Dims& d = dims_;
  const Character& ch = character_;
  const Clothing cl = ch.clothing;
  int slot = 0;
  // Pattern frame of a part: stripes vary along u, so u runs along the part's long axis for
  // hoops around it, or across it for stripes along it.
  auto push = [&](Shape shape, const Material& m, const Vec3& origin, const Vec3& along,
                  const Vec3& across) -> Primitive& {
    Primitive& q = out.emplace_back();
    q.shape = shape;
    q.human = true;
    q.material = ch.stripes_along ? dressed(m, origin, across, along, print_seeds_[slot])
                                  : dressed(m, origin, along, across, print_seeds_[slot]);
    ++slot;
    return q;
  };
  auto cone = [&](const Vec3& a, const Vec3& b, double ra, double rb, const Material& m,
                  const Vec3& across) {
    const Vec3 along = safe_normalized(b - a, Vec3::UnitZ());
    Primitive& q = push(Shape::round_cone, m, a, along, perpendicular_part(across, along));
    q.a = a;
    q.b = b;
    q.ra = ra;
    q.rb = rb;
  };
  auto ellipsoid = [&](const Vec3& c, const Axes& ax, double s_lat, double s_fwd, double s_up,
                       const Material& m, const Vec3& origin) {
    Primitive& q = push(Shape::ellipsoid, m, origin, ax.up, ax.lat);
    q.a = c;
    q.axes.col(0) = ax.lat * s_lat;
    q.axes.col(1) = ax.fwd * s_fwd;
    q.axes.col(2) = ax.up * s_up;
  };

  // Which surfaces carry which cloth.
  const bool coat = cl == Clothing::long_coat, loose = cl == Clothing::loose_shirt;
  const Material& torso_m = ch.top;
  const Material& upper_arm_m = cl == Clothing::dress ? ch.skin : ch.top;
  const Material& forearm_m = coat ? ch.top : ch.skin;
  const Material& pelvis_m = cl == Clothing::dress || coat ? ch.top : ch.bottom;
  const Material& leg_m = cl == Clothing::skirt ? ch.skin : ch.bottom;
  const double torso_scale = coat ? 1.08 : loose ? 1.06 : 1.0;
  const double sleeve = coat ? 10.0 : loose ? 8.0 : 0.0;  // mm of cloth over the arm

  // Head and neck.
  ellipsoid(p[kHead], head_, d.head_side, d.head_depth, head_up_, ch.skin, p[kHead]);
  cone(p[kHead], p[kChin], 0.75 * d.head_side, d.jaw_r, ch.skin, head_.lat);
  cone(p[kNeck], p[kHead], d.neck_r, 0.9 * d.neck_r, ch.skin, head_.lat);

  // Trunk: chest follows the shoulders, belly and pelvis the hips.
  const double shoulder_width = (p[kShoulderL] - p[kShoulderR]).norm();
  const double hip_half_width = 0.5 * (p[kHipL] - p[kHipR]).norm();
  const double spine_upper = (p[kNeck] - p[kChest]).norm();
  const double spine_lower = (p[kChest] - p[kPelvis]).norm();
  // The chest and belly overlap deeply so the trunk has no waist notch where they meet.
  ellipsoid(p[kChest] + 0.5 * (p[kNeck] - p[kChest]), torso_,
            torso_scale * d.chest_lat_per_shoulder * shoulder_width,
            torso_scale * d.chest_depth, 0.62 * spine_upper, torso_m, p[kPelvis]);
  ellipsoid(p[kPelvis] + 0.6 * (p[kChest] - p[kPelvis]), hips_, torso_scale * d.belly_lat,
            torso_scale * d.belly_depth, 0.9 * spine_lower, torso_m, p[kPelvis]);
  // Flanks from the armpits to the waist square the trunk seen from the front.
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? -1.0 : 1.0;
    const double r_waist = 0.8 * torso_scale * d.belly_depth;
    const Vec3 armpit = p[kNeck] + 0.42 * (p[kShoulderR + side] - p[kNeck]) -
                        torso_.up * (0.4 * spine_upper);
    const Vec3 waist = p[kChest] + hips_.lat * (sign * (torso_scale * d.belly_lat - r_waist));
    cone(armpit, waist, 0.7 * torso_scale * d.chest_depth, r_waist, torso_m, torso_.lat);
  }
  const double pelvis_scale = coat ? 1.05 : 1.0;
  ellipsoid(p[kPelvis] - hips_.up * (0.1 * d.pelvis_up), hips_,
            pelvis_scale * (hip_half_width + d.pelvis_lat_extra), pelvis_scale * d.pelvis_depth,
            d.pelvis_up, pelvis_m, p[kPelvis]);

  // Shoulders: from the base of the neck, a little raised (the trapezius), to each joint.
  for (int side = 0; side < 2; ++side)
    cone(p[kNeck] + torso_.up * (0.15 * spine_upper), p[kShoulderR + side], d.neck_r,
         0.9 * d.upper_arm_r0 + sleeve, upper_arm_m, torso_.up);

  // Arms (right then left), across-axis from the chest so sleeve prints turn with it.
  for (int side = 0; side < 2; ++side) {
    const Vec3& sh = p[kShoulderR + side];
    const Vec3& el = p[kElbowR + side];
    const Vec3& wr = p[kWristR + side];
    cone(sh, el, d.upper_arm_r0 + sleeve, d.upper_arm_r1 + sleeve, upper_arm_m, torso_.fwd);
    const double cuff = coat ? sleeve : 0.0;
    cone(el, wr, d.forearm_r0 + cuff, d.forearm_r1 + cuff, forearm_m, torso_.fwd);
    cone(wr, p[kHandTipR + side], d.hand_r0, d.hand_r1, ch.skin, torso_.fwd);
  }
  // Legs, and feet from a heel behind the ankle to the toe.
  for (int side = 0; side < 2; ++side) {
    const Vec3& hip = p[kHipR + side];
    const Vec3& knee = p[kKneeR + side];
    const Vec3& ankle = p[kAnkleR + side];
    const Vec3& toe = p[kToeR + side];
    cone(hip, knee, d.thigh_r0, d.thigh_r1, leg_m, hips_.fwd);
    cone(knee, ankle, d.shin_r0, d.shin_r1, leg_m, hips_.fwd);
    // The toe point is the tip on the floor and the ankle sits above the heel: pull the
    // ends in by their radii so the sole, not the cone's axis, meets the floor.
    const double foot_len = (toe - ankle).norm();
    const Vec3 along = safe_normalized(toe - ankle, hips_.fwd);
    const Vec3 sole_up = perpendicular_part(Vec3::UnitZ(), along);
    cone(ankle - along * (0.2 * foot_len) - sole_up * (0.8 * d.foot_r0),
         toe - along * d.foot_r1 + sole_up * d.foot_r1, d.foot_r0, d.foot_r1, ch.shoes,
         hips_.lat);
  }

  // Hair: a cap over the skull (the face stays bare) and the swinging tail.
  if (ch.hair != Hair::bald) {
    ellipsoid(p[kHead] - head_.fwd * (0.12 * d.head_depth) + head_.up * (0.08 * head_up_),
              head_, 1.06 * d.head_side, 1.04 * d.head_depth, head_up_, ch.hair_material,
              p[kHead]);
  }
  if (hair_active_) {
    const double r[kHairNodes] = {0.75 * d.head_side, 0.6 * d.head_side, 0.45 * d.head_side,
                                  0.25 * d.head_side};
    for (int j = 0; j + 1 < kHairNodes; ++j)
      cone(hair_x_[j], hair_x_[j + 1], r[j], r[j + 1], ch.hair_material, head_.lat);
  }
  if (ch.hat) {
    ellipsoid(p[kHead] + head_.up * (0.62 * head_up_) - head_.fwd * (0.05 * d.head_depth),
              head_, 1.1 * d.head_side, 1.08 * d.head_depth, 0.55 * head_up_, ch.hat_material,
              p[kHead]);
    ellipsoid(p[kHead] + head_.up * (0.45 * head_up_), head_, 1.9 * d.head_side,
              1.75 * d.head_depth, 0.05 * head_up_, ch.hat_material, p[kHead]);
  }

  // Loose cloth from its waistband to the spring-driven hem.
  if (hem_.active) {
    const Vec3 top = p[kPelvis] + hips_.up * hem_.top_offset;
    const Material& m = cl == Clothing::skirt ? ch.bottom : ch.top;
    const Vec3 axis = safe_normalized(top - hem_.x, hips_.up);
    Primitive& q = push(Shape::cone_shell, m, top, axis, perpendicular_part(hips_.lat, axis));
    q.a = top;
    q.b = hem_.x;
    q.ra = hem_.ra;
    q.rb = hem_.r;
  }

  // What tells a front from a back in events: a dark band across the eyes and brows, and a
  // print on the front of the top in a shade far from the top's own. Added last so the
  // other parts keep their print seeds. front_print scales both across and down (0: none):
  // at 2 the print covers most of the chest, as a contrasting shirt under an open jacket.
  const double cue = ch.front_print;
  if (!(cue > 0)) return;
  Material brows;
  brows.albedo = brows.albedo2 = 0.04f;
  ellipsoid(p[kHead] + head_.fwd * (0.85 * d.head_depth) + head_.up * (0.18 * head_up_), head_,
            std::min(0.72 * cue, 0.95) * d.head_side, 0.25 * d.head_depth, 0.14 * cue * head_up_, brows, p[kHead]);
  Material front = torso_m;
  front.pattern = Pattern::plain;
  front.albedo = front.albedo2 = torso_m.albedo < 0.35f ? 0.85f : 0.04f;
  // The print's top edge stays below the collar; a bigger print grows down the chest.
  const double print_up = std::min(0.4 * cue, 0.62) * spine_upper;
  ellipsoid(p[kChest] + 0.5 * (p[kNeck] - p[kChest]) - torso_.up * (print_up - 0.4 * spine_upper) +
                torso_.fwd * (0.8 * torso_scale * d.chest_depth),
            torso_, std::min(0.5 * cue, 0.9) * torso_scale * d.chest_lat_per_shoulder * shoulder_width,
            0.3 * d.chest_depth, print_up, front, p[kPelvis]);
}

}  // namespace yelan::camera::sim
