// Procedural dance. Each move maps time to a vector of joint parameters (pelvis offsets and
// tilts, spine bend, head, per arm elevation/plane/twist/elbow/wrist, per foot offset/lift)
// built from a constant base pose, beat-periodic sines and one-shot sin^2 envelopes, all C1.
// Consecutive moves cross-fade over one beat with a smootherstep weight (C2), and the facing
// (turns, spins) and the jump height are separate C1 events, so the whole motion has
// continuous positions and velocities. The skeleton and its bone lengths are motion.h's.
#include "camera/sim/dance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

const char* dance_move_name(DanceMoveKind k) {
  static const char* names[] = {"groove", "arm_wave", "arm_raise", "torso", "step_touch", "hip_sway",
                                "squat",  "kick",     "turn",      "spin",  "jump"};
  return names[int(k)];
}

DanceParams random_dance_params(std::uint64_t seed) {
  Rng r(seed, 0xDA9CE0001ull);
  DanceParams p;
  p.tempo_bpm = r.uniform(80, 160);
  p.energy = r.uniform(0.3, 1.0);
  p.arm_style = r.uniform();
  p.leg_style = r.uniform();
  p.jump_prob = r.uniform(0, 0.15);
  p.spin_prob = r.uniform(0, 0.15);
  p.turn_prob = r.uniform(0, 0.15);
  p.static_legs = r.uniform() < 0.1;
  return p;
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;
constexpr double kGravity = 9810;  // mm/s^2

// Joint parameters, blended linearly. Angles in radians, offsets in mm (dancer frame:
// x = the dancer's left, y = backwards, z up; the dancer faces -y).
enum Field : int {
  kSwayX, kSwayY, kDrop, kTiltFwd, kTiltSide, kTwistPelvis,
  kBendFwd, kBendSide, kTwistChest,
  kNod, kHeadTurn, kHeadTilt,
  kElev, kPlane = kElev + 2, kArmTwist = kPlane + 2, kFlex = kArmTwist + 2, kWristFlex = kFlex + 2,
  kFootX = kWristFlex + 2, kFootY = kFootX + 2, kLift = kFootY + 2,
  kFieldCount = kLift + 2
};
using Params = std::array<double, kFieldCount>;

double smootherstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (x * (6 * x - 15) + 10);
}

// Cubic Hermite from (p0, v0) to (p1, v1) over duration h, at time s in [0, h].
double hermite(double p0, double v0, double p1, double v1, double h, double s) {
  const double u = s / h, u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * h * v0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * h * v1;
}

// The vertical jump profile (mm, added to the pelvis): crouch, push-off, ballistic flight,
// landing, recovery. Positions and velocities match at every joint of the pieces.
struct Jump {
  double t0 = 0, crouch = 0.25, push = 0.15, flight = 0, land = 0.15, recover = 0.25;
  double depth = 120, v0 = 0, land_depth = 100;
  double total() const { return crouch + push + flight + land + recover; }
  double takeoff() const { return t0 + crouch + push; }
  double at(double t) const {
    double s = t - t0;
    if (s <= 0) return 0;
    if (s < crouch) return hermite(0, 0, -depth, 0, crouch, s);
    s -= crouch;
    if (s < push) return hermite(-depth, 0, 0, v0, push, s);
    s -= push;
    if (s < flight) return v0 * s - 0.5 * kGravity * s * s;
    s -= flight;
    if (s < land) return hermite(0, -v0, -land_depth, 0, land, s);
    s -= land;
    if (s < recover) return hermite(-land_depth, 0, 0, 0, recover, s);
    return 0;
  }
};

struct Move {
  DanceMove info;
  double beat0 = 0;        // start, in beats
  double amp = 1;          // energy-scaled amplitude 0..1
  int side = 0;            // 0 right leads, 1 left leads
  double phase = 0;        // radians
  Params base{};           // the move's held pose
  double a1 = 0, a2 = 0, a3 = 0;  // move-specific amounts
  double yaw_before = 0;   // facing at the move's start
  Jump jump;
};

class Dance final : public ProceduralDance {
 public:
  Dance(const DanceParams& prm, const BodyShape& shape, std::uint64_t seed, double duration)
      : prm_(prm), prop_(body_proportions(shape)), duration_(duration), seed_(seed) {
    auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
    if (!in(prm.tempo_bpm, 40, 240) || !in(prm.energy, 0, 1) || !in(prm.arm_style, 0, 1) ||
        !in(prm.leg_style, 0, 1) || !in(prm.jump_prob, 0, 1) || !in(prm.spin_prob, 0, 1) ||
        !in(prm.turn_prob, 0, 1))
      throw std::invalid_argument("dance parameters out of range (tempo 40..240 bpm, the rest 0..1)");
    if (!(duration > 0 && duration < 1e6)) throw std::invalid_argument("dance duration must be in (0, 1e6) s");
    beat_s_ = 60.0 / prm.tempo_bpm;
    leg_ = prop_.thigh + prop_.shank;
    stand_ = prop_.ankle_height + 0.975 * leg_;  // relaxed knees
    toe_pitch0_ = std::asin(std::clamp((prop_.ankle_height - 0.009 * shape.height_mm) / prop_.foot, 0.0, 0.9));
    plan(seed);
  }

  double duration_s() const override { return duration_; }
  std::string name() const override { return "dance-" + std::to_string(seed_); }
  const std::vector<DanceMove>& moves() const override { return infos_; }

  BodyPose at(double t) const override {
    t = std::clamp(t, 0.0, duration_);
    const std::size_t i = move_index(t);
    const Move& m = moves_[i];
    Params p = eval(m, t);
    const double w = i == 0 ? 1 : smootherstep((t - m.info.t0_s) / beat_s_);
    if (w < 1) {
      const Params q = eval(moves_[i - 1], t);
      for (int k = 0; k < kFieldCount; ++k) p[k] = w * p[k] + (1 - w) * q[k];
    }
    double yaw = m.yaw_before, jump = 0;
    if (m.info.yaw_change_rad != 0)
      yaw += m.info.yaw_change_rad *
             smootherstep((t - m.info.event_t0_s) / (m.info.event_t1_s - m.info.event_t0_s));
    if (m.info.kind == DanceMoveKind::jump) jump = m.jump.at(t);
    if (prm_.static_legs) {
      for (int k : {kSwayX, kSwayY, kDrop, kTiltFwd, kTiltSide, kTwistPelvis}) p[k] = 0;
      for (int s = 0; s < 2; ++s) p[kFootX + s] = p[kFootY + s] = p[kLift + s] = 0;
      yaw = 0, jump = 0;
    }
    return build(p, yaw, jump);
  }

 private:
  std::size_t move_index(double t) const {
    auto it = std::upper_bound(starts_.begin(), starts_.end(), t);
    return it == starts_.begin() ? 0 : std::size_t(it - starts_.begin()) - 1;
  }

  // ---------------------------------------------------------------- the phrase

  void plan(std::uint64_t seed) {
    Rng r(seed, 0xDA9CE0002ull);
    const double e = prm_.energy;
    struct W { DanceMoveKind k; double w; };
    std::vector<W> weights;
    const double special = prm_.static_legs ? 0 : prm_.jump_prob + prm_.spin_prob + prm_.turn_prob;
    const double rest = std::max(0.0, 1 - special);
    const double as = prm_.arm_style, ls = prm_.leg_style;
    if (prm_.static_legs) {
      weights = {{DanceMoveKind::groove, 0.3}, {DanceMoveKind::arm_wave, 1 - as + 0.2},
                 {DanceMoveKind::arm_raise, as + 0.2}, {DanceMoveKind::torso, 0.4}};
    } else {
      const std::vector<W> plain = {{DanceMoveKind::groove, 0.5},          {DanceMoveKind::arm_wave, 0.6 * (1 - as) + 0.1},
                                    {DanceMoveKind::arm_raise, 0.6 * as + 0.1}, {DanceMoveKind::torso, 0.2},
                                    {DanceMoveKind::step_touch, 1 - ls + 0.1}, {DanceMoveKind::hip_sway, 0.7 * (1 - ls) + 0.1},
                                    {DanceMoveKind::squat, 0.6 * ls + 0.1},    {DanceMoveKind::kick, 0.5 * ls + 0.05}};
      double sum = 0;
      for (auto& w : plain) sum += w.w;
      for (auto& w : plain) weights.push_back({w.k, w.w / sum * rest});
      weights.push_back({DanceMoveKind::jump, prm_.jump_prob});
      weights.push_back({DanceMoveKind::spin, prm_.spin_prob});
      weights.push_back({DanceMoveKind::turn, prm_.turn_prob});
    }
    double total_w = 0;
    for (auto& w : weights) total_w += w.w;
    double beat = 0, yaw = 0;
    DanceMoveKind last = DanceMoveKind::groove;
    const double end_beat = duration_ / beat_s_ + 1;
    while (beat < end_beat || moves_.empty()) {
      DanceMoveKind k = weights.front().k;
      double x = r.uniform() * total_w;
      for (auto& w : weights) {
        k = w.k;
        if ((x -= w.w) < 0) break;
      }
      const bool special_move = k == DanceMoveKind::jump || k == DanceMoveKind::spin || k == DanceMoveKind::turn;
      if (special_move && (last == k || moves_.empty())) k = DanceMoveKind::groove;  // settle first
      Move m;
      m.info.kind = k;
      m.amp = e * r.uniform(0.6, 1.0);
      m.side = r.uniform() < 0.5;
      m.phase = r.uniform(0, 2 * kPi);
      m.a1 = r.uniform(), m.a2 = r.uniform(), m.a3 = r.uniform();
      int beats = r.uniform() < 0.5 ? 4 : (r.uniform() < 0.5 ? 2 : 8);
      m.base = base_pose(r, k, m);
      m.yaw_before = yaw;
      const double t0 = beat * beat_s_;
      m.info.t0_s = t0;
      if (k == DanceMoveKind::spin) {
        // The retire is set up after the one-beat cross-fade (so the previous move's lifted
        // foot is down first), the turn happens on it, and it is undone a beat before the end.
        beats = std::max(5, int(std::ceil(2.75 + 0.8 / beat_s_)));
        m.info.event_t0_s = t0 + 1.75 * beat_s_;
        m.info.event_t1_s = t0 + (beats - 1) * beat_s_;
        m.info.yaw_change_rad = (m.side ? 2 : -2) * kPi;
      } else if (k == DanceMoveKind::turn) {
        beats = 4;
        m.info.event_t0_s = t0 + 0.5 * beat_s_;
        m.info.event_t1_s = t0 + 2.5 * beat_s_;
        m.info.yaw_change_rad = (m.side ? 1 : -1) * (m.a1 < 0.5 ? 0.5 : 1.0) * kPi;
      } else if (k == DanceMoveKind::jump) {
        Jump& j = m.jump;
        const double height = 60 + 140 * m.amp;  // apex, mm
        j.v0 = std::sqrt(2 * kGravity * height);
        j.flight = 2 * j.v0 / kGravity;
        j.push = std::min(0.15, 2.7 * j.depth / j.v0);      // keeps the Hermite monotonic
        j.land = std::min(0.15, 2.7 * j.land_depth / j.v0);
        j.t0 = t0 + 0.5 * beat_s_;
        beats = int(std::ceil((j.total() + 0.5 * beat_s_) / beat_s_)) + 1;
        m.info.event_t0_s = j.takeoff();
        m.info.event_t1_s = j.takeoff() + j.flight;
      }
      m.info.t1_s = t0 + beats * beat_s_;
      m.beat0 = beat;
      yaw += m.info.yaw_change_rad;
      beat += beats;
      last = k;
      moves_.push_back(m);
    }
    for (const Move& m : moves_) {
      starts_.push_back(m.info.t0_s);
      infos_.push_back(m.info);
    }
  }

  // The pose a move holds (before its oscillations): arms somewhere between down and up.
  Params base_pose(Rng& r, DanceMoveKind k, const Move& m) const {
    Params b{};
    for (int s = 0; s < 2; ++s) {
      b[kElev + s] = r.uniform(15, 60) * kDeg;
      b[kPlane + s] = r.uniform(0, 60) * kDeg;
      b[kArmTwist + s] = r.uniform(-20, 40) * kDeg;
      b[kFlex + s] = r.uniform(20, 70) * kDeg;
      b[kWristFlex + s] = r.uniform(-10, 10) * kDeg;
    }
    b[kBendFwd] = r.uniform(-0.05, 0.15) * m.amp;
    b[kNod] = r.uniform(-0.1, 0.15);
    b[kHeadTurn] = r.uniform(-0.3, 0.3) * m.amp;
    if (k == DanceMoveKind::spin) {  // arms rounded in front, as in a pirouette
      for (int s = 0; s < 2; ++s) {
        b[kElev + s] = 70 * kDeg, b[kPlane + s] = 75 * kDeg, b[kFlex + s] = 70 * kDeg, b[kArmTwist + s] = 0;
      }
      b[kHeadTurn] = 0;
    }
    if (k == DanceMoveKind::jump)
      for (int s = 0; s < 2; ++s) b[kElev + s] = r.uniform(40, 120) * kDeg, b[kFlex + s] = r.uniform(10, 40) * kDeg;
    return b;
  }

  // The move's parameters at time t (valid for any t, also past the move's end, where its
  // periodic parts keep going and its one-shot parts are zero).
  Params eval(const Move& m, double t) const {
    Params p = m.base;
    const double ab = t / beat_s_;                // beats since the dance began
    const double b = ab - m.beat0;                // beats into the move
    const double len = (m.info.t1_s - m.info.t0_s) / beat_s_;
    const double A = m.amp;
    const int L = m.side, R = 1 - m.side;        // leading and other side
    const double c = std::cos(2 * kPi * b), s = std::sin(2 * kPi * b);
    const double c2 = std::cos(kPi * b + m.phase), s2 = std::sin(kPi * b + m.phase);
    // A light bounce on every beat in every move except the held ones.
    auto bounce = [&](double mm) { p[kDrop] += mm * A * (1 - c) / 2; };
    switch (m.info.kind) {
      case DanceMoveKind::groove:
        bounce(30);
        p[kNod] += 0.12 * A * s;
        p[kTwistChest] += 0.15 * A * s2;
        for (int k = 0; k < 2; ++k) {
          p[kElev + k] += 15 * kDeg * A * (k ? s2 : -s2);
          p[kFlex + k] += 20 * kDeg * A * (1 + (k ? c2 : -c2)) / 2;
        }
        break;
      case DanceMoveKind::arm_wave:
        bounce(15);
        for (int k = 0; k < 2; ++k) {
          const double ph = kPi * b * 0.5 + m.phase + (k ? 0 : kPi * m.a1);
          p[kElev + k] = (90 + 50 * A * std::sin(ph)) * kDeg;                // 40..140 deg
          p[kPlane + k] = (20 + 30 * m.a2) * kDeg;
          p[kFlex + k] = (60 + 50 * A * std::sin(ph + kPi / 2)) * kDeg;      // 10..110 deg
          p[kArmTwist + k] = (30 + 40 * A * std::sin(ph - kPi / 3)) * kDeg;
          p[kWristFlex + k] = 25 * kDeg * A * std::sin(ph + kPi);
        }
        p[kBendSide] += 0.12 * A * s2;
        break;
      case DanceMoveKind::arm_raise: {
        bounce(25);
        const double sharp = 1 + 2 * prm_.arm_style;
        for (int k = 0; k < 2; ++k) {
          // Alternate arms every beat: a sin^2 pulse raised to a power (sharper, still C1).
          const double x = b * 0.5 + (k == L ? 0 : 0.5);
          const double pulse = std::pow(std::pow(std::sin(kPi * x), 2), sharp);
          p[kElev + k] = p[kElev + k] + (160 * kDeg - p[kElev + k]) * A * pulse;
          p[kFlex + k] = p[kFlex + k] * (1 - pulse) + 5 * kDeg * pulse;
          p[kPlane + k] = p[kPlane + k] * (1 - pulse) + (m.a2 < 0.5 ? 10 : 80) * kDeg * pulse;
        }
        break;
      }
      case DanceMoveKind::torso:
        p[kBendFwd] += 0.25 * A * (1 - c2) / 2;
        p[kBendSide] += 0.2 * A * s2;
        p[kTwistChest] += 0.35 * A * std::sin(kPi * b * 0.5 + m.phase);
        p[kHeadTilt] += 0.15 * A * s2;
        for (int k = 0; k < 2; ++k) p[kElev + k] += 20 * kDeg * A * (1 + (k ? s2 : -s2)) / 2;
        break;
      case DanceMoveKind::step_touch: {
        // Over 4 beats: the right foot steps out and back (beats 0-2 of every 4 counted from
        // the dance's start, so consecutive moves and kicks never lift both feet), then the left.
        const double w = (0.9 + 1.1 * A) * prop_.half_hip;
        for (int k = 0; k < 2; ++k) {
          const double q = std::fmod(ab + (k == 0 ? 0 : 2), 4.0);   // 0..4
          const double out = q < 2 ? (1 - std::cos(kPi * q)) / 2 : 0;
          const double lift = q < 2 ? std::pow(std::sin(kPi * q), 2) : 0;
          p[kFootX + k] = (k ? 1 : -1) * w * out;
          p[kLift + k] = 60 * A * lift;
          p[kSwayX] += (k ? 1 : -1) * 0.4 * w * out;
        }
        bounce(20);
        for (int k = 0; k < 2; ++k) p[kElev + k] += 25 * kDeg * A * (1 - std::cos(kPi * b)) / 2;
        break;
      }
      case DanceMoveKind::hip_sway:
        p[kSwayX] += 70 * A * std::sin(kPi * b + (L ? 0 : kPi));
        p[kTiltSide] += -0.08 * A * std::sin(kPi * b + (L ? 0 : kPi));
        p[kTwistPelvis] += 0.1 * A * std::cos(kPi * b);
        p[kBendSide] += 0.1 * A * std::sin(kPi * b + (L ? 0 : kPi));
        bounce(20);
        break;
      case DanceMoveKind::squat:
        p[kDrop] += (0.12 + 0.16 * A) * leg_ * (1 - std::cos(kPi * b)) / 2;   // down and up in 2 beats
        p[kBendFwd] += 0.25 * A * (1 - std::cos(kPi * b)) / 2;
        for (int k = 0; k < 2; ++k) {
          p[kFootX + k] = (k ? 1 : -1) * 0.8 * prop_.half_hip * m.a1;  // wider stance
          p[kElev + k] += (80 * kDeg - p[kElev + k]) * (1 - std::cos(kPi * b)) / 2 * A;
          p[kPlane + k] = 85 * kDeg;
        }
        break;
      case DanceMoveKind::kick: {
        // A kick every 2 beats, legs alternating in step with step_touch: forward and up.
        for (int k = 0; k < 2; ++k) {
          const double x = std::fmod(ab * 0.5 + (k == 0 ? 0 : 0.5), 1.0) * 2;   // 0..2
          const double env = x < 1 ? std::pow(std::sin(kPi * x), 2) : 0;
          p[kFootY + k] = -(0.25 + 0.35 * A) * leg_ * env;
          p[kLift + k] = (0.15 + 0.45 * A) * leg_ * env;
          p[kSwayX] += (k ? -1 : 1) * 0.6 * prop_.half_hip * env;     // weight onto the other leg
          p[kTiltFwd] += -0.08 * A * env;                              // lean back a little
          p[kElev + k] += 30 * kDeg * A * env;
        }
        break;
      }
      case DanceMoveKind::turn:
        bounce(20);
        break;
      case DanceMoveKind::spin: {
        // Retire: the standing foot moves under the body's axis (so it pivots in place rather
        // than circling), the free foot is drawn up to the standing knee, then both return.
        const double env = smootherstep((b - 1) / 0.75) * (1 - smootherstep((b - (len - 1)) / 0.75));
        const int free_leg = R, support = L;
        p[kFootX + support] = (support ? -1 : 1) * prop_.half_hip * env;
        p[kLift + free_leg] = 0.35 * leg_ * env;
        p[kFootX + free_leg] = (free_leg ? -1 : 1) * 0.7 * prop_.half_hip * env;
        break;
      }
      case DanceMoveKind::jump:
        break;
    }
    return p;
  }

  // ---------------------------------------------------------------- the skeleton

  static Eigen::Matrix3d rz(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }
  static Eigen::Matrix3d rx(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
  static Eigen::Matrix3d ry(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }

  BodyPose build(const Params& p, double yaw, double jump) const {
    const BodyProportions& P = prop_;
    BodyPose out;
    auto& q = out.p;
    const Eigen::Matrix3d ryaw = rz(yaw);
    q[kPelvis] = ryaw * Vec3(p[kSwayX], p[kSwayY], stand_ - p[kDrop] + jump);
    // Positive x-rotation tips +z towards -y: a forward bend for a dancer facing -y.
    const Eigen::Matrix3d rpel = ryaw * rz(p[kTwistPelvis]) * rx(p[kTiltFwd]) * ry(p[kTiltSide]);
    const Eigen::Matrix3d rc1 = rpel * rz(p[kTwistChest] / 2) * rx(p[kBendFwd] / 2) * ry(p[kBendSide] / 2);
    const Eigen::Matrix3d rc2 = rc1 * rz(p[kTwistChest] / 2) * rx(p[kBendFwd] / 2) * ry(p[kBendSide] / 2);
    q[kChest] = q[kPelvis] + P.pelvis_chest * rc1.col(2);
    q[kNeck] = q[kChest] + P.chest_neck * rc2.col(2);
    const Eigen::Matrix3d rh = rc2 * rz(p[kHeadTurn]) * rx(p[kNod]) * ry(p[kHeadTilt]);
    const Vec3 hu = rh.col(2), hf = -rh.col(1);
    q[kHead] = q[kNeck] + P.neck_head * (rh * Vec3(0, -0.15, 1).normalized());
    q[kHeadTop] = q[kHead] + P.head_top * hu;
    q[kNose] = q[kHead] + P.nose_fwd * hf + P.nose_up * hu;
    q[kChin] = q[kHead] + P.chin_fwd * hf + P.chin_up * hu;
    for (int k = 0; k < 2; ++k) {
      const double sg = k ? 1 : -1;  // left is +x
      // Arm: abduct by the elevation in the chest's frontal plane, swing it forward by the
      // plane angle, twist about its own axis; the elbow flexes towards the rotated front.
      const Eigen::Matrix3d ra = rc2 * rz(-p[kPlane + k] * sg) * ry(-p[kElev + k] * sg) * rz(p[kArmTwist + k] * sg);
      const Vec3 u = -ra.col(2), bend = -ra.col(1);
      const double fl = p[kFlex + k], wf = fl + p[kWristFlex + k];
      q[kShoulderR + k] = q[kNeck] + P.half_shoulder * (rc2 * Vec3(sg, 0, 0));
      q[kElbowR + k] = q[kShoulderR + k] + P.upper_arm * u;
      q[kWristR + k] = q[kElbowR + k] + P.forearm * (std::cos(fl) * u + std::sin(fl) * bend);
      q[kHandTipR + k] = q[kWristR + k] + P.hand * (std::cos(wf) * u + std::sin(wf) * bend);
      // Leg: two-bone IK from the hip to the ankle target over the (lifted) foot.
      q[kHipR + k] = q[kPelvis] + P.half_hip * (rpel * Vec3(sg, 0, 0));
      const Vec3 home(sg * P.half_hip + p[kFootX + k], p[kFootY + k], 0);
      const double lift = p[kLift + k];  // jumps lift the feet through the IK's capped reach
      const Vec3 target = ryaw * home + Vec3(0, 0, P.ankle_height + lift);
      const Vec3 lateral = ryaw * Vec3(1, 0, 0);
      leg_ik(q[kHipR + k], target, lateral, q[kKneeR + k], q[kAnkleR + k]);
      // A raised foot points its toes (smoothly, up to ~halfway to vertical).
      const double pitch = toe_pitch0_ + 0.5 * std::tanh(lift / (0.3 * leg_)) * (kPi / 2 - toe_pitch0_);
      q[kToeR + k] = q[kAnkleR + k] + P.foot * (std::cos(pitch) * (ryaw * Vec3(0, -1, 0)) - std::sin(pitch) * Vec3::UnitZ());
    }
    return out;
  }

  // Knee forward of the hip-ankle line (n x lateral), reach softly capped below full
  // extension with a tanh knee so the ankle follows the hip up (jumps) smoothly.
  void leg_ik(const Vec3& hip, const Vec3& target, const Vec3& lateral, Vec3& knee, Vec3& ankle) const {
    const double a = prop_.thigh, b = prop_.shank, reach = a + b;
    Vec3 d = target - hip;
    double dist = d.norm();
    const Vec3 n = dist > 1e-9 ? Vec3(d / dist) : Vec3(-Vec3::UnitZ());
    const double d0 = 0.985 * reach, lim = 0.9995 * reach;
    if (dist > d0) dist = d0 + (lim - d0) * std::tanh((dist - d0) / (lim - d0));
    dist = std::max(dist, 0.35 * reach);  // never folds past ~140 deg (squats stay above)
    ankle = hip + dist * n;
    Vec3 m = n.cross(lateral);
    m = m.norm() > 1e-9 ? Vec3(m.normalized()) : Vec3(-Vec3::UnitY());
    const double cos_h = std::clamp((a * a + dist * dist - b * b) / (2 * a * dist), -1.0, 1.0);
    knee = hip + a * (cos_h * n + std::sqrt(1 - cos_h * cos_h) * m);
  }

  DanceParams prm_;
  BodyProportions prop_;
  double duration_;
  std::uint64_t seed_;
  double beat_s_ = 0.5, leg_ = 0, stand_ = 0, toe_pitch0_ = 0;
  std::vector<Move> moves_;
  std::vector<double> starts_;
  std::vector<DanceMove> infos_;
};

}  // namespace

std::unique_ptr<ProceduralDance> make_procedural_dance(const DanceParams& params, const BodyShape& shape,
                                                       std::uint64_t seed, double duration_s) {
  return std::make_unique<Dance>(params, shape, seed, duration_s);
}

}  // namespace yelan::camera::sim
