// Procedural dance: deterministic per seed, rigid bones, continuous positions and velocities
// (also across move boundaries and the pieces of a jump), feet on the floor, knees and elbows
// bending one way, spins turning a full circle, static legs staying still.
#include <catch2/catch.hpp>
#include <cmath>

#include "camera/sim/dance.h"
#include "camera/sim/rng.h"

using namespace yelan::camera::sim;

namespace {

double max_diff(const BodyPose& a, const BodyPose& b) {
  double d = 0;
  for (int i = 0; i < kBodyPointCount; ++i) d = std::max(d, (a.p[i] - b.p[i]).norm());
  return d;
}

// Facing angle about z from the hips (the left hip is on the dancer's left).
double facing(const BodyPose& p) {
  const Vec3 f = (p.p[kHipL] - p.p[kHipR]).cross(Vec3::UnitZ());
  return std::atan2(f.y(), f.x());
}

DanceParams lively() {
  DanceParams p;
  p.tempo_bpm = 131;
  p.energy = 0.9;
  p.jump_prob = 0.25;
  p.spin_prob = 0.25;
  p.turn_prob = 0.15;
  return p;
}

bool airborne(const ProceduralDance& d, double t) {
  for (const DanceMove& m : d.moves())
    if (m.kind == DanceMoveKind::jump && t > m.event_t0_s - 0.1 && t < m.event_t1_s + 0.1) return true;
  return false;
}

}  // namespace

TEST_CASE("motion dance is deterministic for a seed and differs between seeds") {
  BodyShape shape;
  const DanceParams p = random_dance_params(5);
  CHECK(random_dance_params(5).tempo_bpm == p.tempo_bpm);
  CHECK(random_dance_params(6).tempo_bpm != p.tempo_bpm);
  const auto a = make_procedural_dance(p, shape, 42, 20);
  const auto b = make_procedural_dance(p, shape, 42, 20);
  const auto c = make_procedural_dance(p, shape, 43, 20);
  CHECK(a->name() == "dance-42");
  CHECK(a->duration_s() == 20);
  int differ = 0;
  for (int i = 0; i < 50; ++i) {
    const double t = 20 * uniform01(1, 1, i);
    CHECK(max_diff(a->at(t), b->at(t)) == 0);
    differ += max_diff(a->at(t), c->at(t)) > 10;
  }
  CHECK(differ > 40);
  REQUIRE(a->moves().size() == b->moves().size());
  CHECK(a->moves().front().t0_s == 0);
  CHECK(a->moves().back().t1_s >= 20);
  CHECK_THROWS_AS(make_procedural_dance(p, shape, 1, 0), std::invalid_argument);
  DanceParams bad = p;
  bad.energy = 1.5;
  CHECK_THROWS_AS(make_procedural_dance(bad, shape, 1, 10), std::invalid_argument);
}

TEST_CASE("motion dance keeps the skeleton's bone lengths") {
  for (int k = 0; k < 8; ++k) {
    BodyShape shape;
    shape.height_mm = 1500 + 450 * uniform01(2, 1, k);
    shape.female = k % 2;
    const auto d = make_procedural_dance(k % 2 ? lively() : random_dance_params(k), shape, k, 30);
    const auto bones = body_bones(shape);
    for (int i = 0; i < 200; ++i) {
      const BodyPose p = d->at(30 * uniform01(2, 2, k * 1000 + i));
      for (const Bone& b : bones) CHECK(std::abs((p.p[b.a] - p.p[b.b]).norm() / b.length_mm - 1) < 1e-9);
    }
  }
}

TEST_CASE("motion dance positions and velocities are continuous") {
  BodyShape shape;
  shape.height_mm = 1760;
  for (std::uint64_t seed : {3u, 4u, 17u}) {
    INFO(seed);
    const auto d = make_procedural_dance(lively(), shape, seed, 40);
    // Where a discontinuity would hide: move starts, ends of the cross-fades, event edges and
    // the pieces of each jump, plus random times.
    std::vector<double> ts;
    const double beat = 60 / lively().tempo_bpm;
    for (const DanceMove& m : d->moves()) {
      for (double t : {m.t0_s, m.t0_s + beat, m.event_t0_s, m.event_t1_s}) ts.push_back(t);
      if (m.kind == DanceMoveKind::jump)
        for (double dt : {-0.4, -0.15, 0.0, 0.05, 0.15, 0.4}) ts.push_back(m.event_t0_s + dt), ts.push_back(m.event_t1_s + dt);
    }
    for (int i = 0; i < 400; ++i) ts.push_back(40 * uniform01(seed, 9, i));
    const double h = 1e-5;
    double worst_dv = 0, worst_step = 0;
    for (double t : ts) {
      if (t < 2 * h || t > 40 - 2 * h) continue;
      const BodyPose a = d->at(t - h), b = d->at(t), c = d->at(t + h);
      for (int i = 0; i < kBodyPointCount; ++i) {
        // One-sided velocities (mm/s) either side of t: their difference is acceleration x h.
        const Vec3 v_before = (b.p[i] - a.p[i]) / h, v_after = (c.p[i] - b.p[i]) / h;
        worst_dv = std::max(worst_dv, (v_after - v_before).norm());
      }
      worst_step = std::max(worst_step, max_diff(d->at(t), d->at(std::min(40.0, t + 0.001))));
    }
    // 2000 m/s^2 x 10 us = 20 mm/s: any true velocity jump above 2 cm/s fails this.
    CHECK(worst_dv < 20);
    CHECK(worst_step < 15);  // under 15 m/s anywhere
  }
}

TEST_CASE("motion dance feet stay on or above the floor, joints bend one way") {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    INFO(seed);
    BodyShape shape;
    shape.height_mm = 1550 + 60 * seed;
    shape.female = seed % 2;
    const BodyProportions prop = body_proportions(shape);
    const auto d = make_procedural_dance(seed % 2 ? lively() : random_dance_params(seed), shape, seed, 30);
    int lifted = 0, lifting_moves = 0;
    for (const DanceMove& m : d->moves())
      lifting_moves += m.t1_s < 30 && (m.kind == DanceMoveKind::step_touch || m.kind == DanceMoveKind::kick ||
                                       m.kind == DanceMoveKind::jump || m.kind == DanceMoveKind::spin);
    for (double t = 0; t <= 30; t += 0.007) {
      const BodyPose p = d->at(t);
      for (int s = 0; s < 2; ++s) {
        const double ankle = p.p[kAnkleR + s].z();
        CHECK(ankle >= prop.ankle_height - 1e-6);  // 0.039 H >= 58 mm
        CHECK(p.p[kToeR + s].z() > 0);
        if (ankle > prop.ankle_height + 50) ++lifted;
        // Knee in front: (thigh x shank) points along the pelvis's left axis.
        const Vec3 left = (p.p[kHipL] - p.p[kHipR]).normalized();
        const Vec3 thigh = p.p[kKneeR + s] - p.p[kHipR + s], shank = p.p[kAnkleR + s] - p.p[kKneeR + s];
        CHECK(thigh.cross(shank).dot(left) > -1e-6 * thigh.norm() * shank.norm());
        // Elbow flexion 0..150 deg.
        const Vec3 upper = p.p[kElbowR + s] - p.p[kShoulderR + s], fore = p.p[kWristR + s] - p.p[kElbowR + s];
        const double flex = std::acos(std::clamp(upper.dot(fore) / upper.norm() / fore.norm(), -1.0, 1.0));
        CHECK(flex <= 150.5 * 3.14159265358979 / 180);
      }
      if (!airborne(*d, t)) CHECK(std::min(p.p[kAnkleR].z(), p.p[kAnkleL].z()) < prop.ankle_height + 1);
      CHECK(p.p[kHead].z() > p.p[kPelvis].z() + 300);
    }
    CHECK((lifted > 0) == (lifting_moves > 0));  // steps, kicks, spins and jumps lift the feet
  }
}

TEST_CASE("motion dance spins turn the facing a full circle and jumps leave the floor") {
  BodyShape shape;
  int spins = 0, jumps = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const auto d = make_procedural_dance(lively(), shape, seed, 40);
    const BodyProportions prop = body_proportions(shape);
    for (const DanceMove& m : d->moves()) {
      if (m.t1_s > 40) break;
      if (m.kind == DanceMoveKind::spin) {
        ++spins;
        CHECK(std::abs(m.yaw_change_rad) == Approx(2 * 3.14159265358979));
        double turned = 0, prev = facing(d->at(m.t0_s));
        for (double t = m.t0_s; t <= m.t1_s; t += 0.004) {
          const double a = facing(d->at(t));
          turned += std::remainder(a - prev, 2 * 3.14159265358979);
          prev = a;
        }
        CHECK(turned * 180 / 3.14159265358979 == Approx(m.yaw_change_rad * 180 / 3.14159265358979).margin(15));
      }
      if (m.kind == DanceMoveKind::jump) {
        ++jumps;
        const BodyPose apex = d->at((m.event_t0_s + m.event_t1_s) / 2);
        CHECK(std::min(apex.p[kAnkleR].z(), apex.p[kAnkleL].z()) > prop.ankle_height + 30);
        const BodyPose before = d->at(m.t0_s + 0.01), top = apex;
        CHECK(top.p[kPelvis].z() > before.p[kPelvis].z() + 50);
      }
    }
  }
  CHECK(spins >= 2);
  CHECK(jumps >= 2);
}

TEST_CASE("motion dance with static legs moves only the upper body") {
  DanceParams p = lively();
  p.static_legs = true;
  BodyShape shape;
  const auto d = make_procedural_dance(p, shape, 77, 25);
  const BodyPose p0 = d->at(0);
  double arm_travel = 0;
  for (double t = 0; t <= 25; t += 0.01) {
    const BodyPose q = d->at(t);
    for (int i : {kPelvis, kHipR, kHipL, kKneeR, kKneeL, kAnkleR, kAnkleL, kToeR, kToeL})
      CHECK((q.p[i] - p0.p[i]).norm() == 0);
    arm_travel = std::max(arm_travel, (q.p[kWristR] - p0.p[kWristR]).norm());
  }
  CHECK(arm_travel > 200);
  for (const DanceMove& m : d->moves()) {
    CHECK(m.kind != DanceMoveKind::jump);
    CHECK(m.kind != DanceMoveKind::spin);
    CHECK(m.kind != DanceMoveKind::kick);
  }
}
