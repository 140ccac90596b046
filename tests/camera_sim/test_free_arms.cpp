// Free arms: rigid bones, only the arms move, the angles mean what they say, the whole range
// is reached, positions and velocities are continuous, the same seed gives the same arms; the
// simulator and the dataset carry the seed.
#include <catch2/catch.hpp>

#include <cmath>

#include <nlohmann/json.hpp>

#include "camera/sim/dance.h"
#include "camera/sim/dataset.h"
#include "camera/sim/free_arms.h"
#include "camera/sim/presets.h"
#include "camera/sim/simulator.h"

using namespace yelan::camera::sim;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;

bool is_arm(int point) {
  for (BodyPoint a : kRightArmPoints)
    if (point == a || point == a + 1) return true;
  return false;
}

std::unique_ptr<ProceduralDance> dance(const BodyShape& shape, double duration_s) {
  return make_procedural_dance(random_dance_params(11), shape, 11, duration_s);
}

}  // namespace

TEST_CASE("free arms: bones rigid, only the arms move, the whole range reached, smoothly", "[sim]") {
  BodyShape shape;
  shape.height_mm = 1630;
  shape.female = true;
  const double duration = 60;
  const auto body = dance(shape, duration + 2);
  const FreeArms arms(shape, 7, duration);
  const auto bones = body_bones(shape);
  double elev[2] = {9, -9}, plane[2] = {9, -9}, flex[2] = {9, -9};
  double worst_speed = 0, worst_dv = 0;
  const double dt = 1e-3;
  for (double t = 0; t < duration; t += 0.0371) {
    const BodyPose b = body->at(t), p = arms.apply(b, t);
    for (const Bone& bone : bones) CHECK(std::abs((p.p[bone.a] - p.p[bone.b]).norm() / bone.length_mm - 1) < 1e-9);
    for (int point = 0; point < kBodyPointCount; ++point)
      if (!is_arm(point) || point == kShoulderR || point == kShoulderL) CHECK((p.p[point] - b.p[point]).norm() == 0);
    for (int side = 0; side < 2; ++side) {
      const ArmAngles a = arms.angles(side, t);
      elev[0] = std::min(elev[0], a.elevation), elev[1] = std::max(elev[1], a.elevation);
      plane[0] = std::min(plane[0], a.plane), plane[1] = std::max(plane[1], a.plane);
      flex[0] = std::min(flex[0], a.flex), flex[1] = std::max(flex[1], a.flex);
    }
    // The hand's speed and its change over a millisecond, the body's own motion included.
    const Vec3 h0 = arms.apply(body->at(t), t).p[kWristR], h1 = arms.apply(body->at(t + dt), t + dt).p[kWristR],
               h2 = arms.apply(body->at(t + 2 * dt), t + 2 * dt).p[kWristR];
    const Vec3 v1 = (h1 - h0) / dt, v2 = (h2 - h1) / dt;
    worst_speed = std::max(worst_speed, v1.norm());
    worst_dv = std::max(worst_dv, (v2 - v1).norm());
  }
  // Keys every 0.3-1.2 s across the range: hanging and overhead, behind and across, straight
  // and folded; the curve never leaves the range between keys.
  CHECK(elev[0] >= 0);
  CHECK(elev[0] < 25 * kDeg);
  CHECK(elev[1] > 150 * kDeg);
  CHECK(elev[1] <= 175 * kDeg + 1e-12);
  CHECK(plane[0] < -15 * kDeg);
  CHECK(plane[1] > 90 * kDeg);
  CHECK(flex[0] >= 0);
  CHECK(flex[0] < 20 * kDeg);
  CHECK(flex[1] > 120 * kDeg);
  CHECK(flex[1] <= 145 * kDeg + 1e-12);
  // A dancer's hands reach ~10 m/s; a jump in velocity would show as metres per second in
  // one millisecond (the curve's acceleration is at most a few hundred m/s^2).
  CHECK(worst_speed < 15000);
  CHECK(worst_dv < 1000 * dt * 1000);
  // The same seed, the same arms; another seed, others.
  const FreeArms again(shape, 7, duration), other(shape, 8, duration);
  for (double t : {0.0, 1.3, 17.7, 59.0}) {
    const BodyPose b = body->at(t);
    for (int side = 0; side < 2; ++side) {
      CHECK((again.apply(b, t).p[kWristR + side] - arms.apply(b, t).p[kWristR + side]).norm() == 0);
      CHECK((other.apply(b, t).p[kWristR + side] - arms.apply(b, t).p[kWristR + side]).norm() > 1);
    }
  }
  CHECK_THROWS_AS(FreeArms(shape, 0, duration), std::invalid_argument);
  CHECK_THROWS_AS(FreeArms(shape, 7, 0), std::invalid_argument);
  CHECK_THROWS_AS(arms.angles(2, 0), std::invalid_argument);
}

TEST_CASE("free arms: the angles mean the procedural dance's (raised sideways, swung forward, folded)", "[sim]") {
  BodyShape shape;
  const BodyProportions P = body_proportions(shape);
  const BodyPose b = dance(shape, 3)->at(0.0);
  const Vec3 up = (b.p[kNeck] - b.p[kChest]).normalized();
  Vec3 left = b.p[kShoulderL] - b.p[kShoulderR];
  left = (left - left.dot(up) * up).normalized();
  const Vec3 forward = left.cross(up);  // the dancer faces -y: left x up
  const auto hold = [&](double elev, double plane, double flex) {
    ArmRange r;
    r.elevation[0] = r.elevation[1] = elev;
    r.plane[0] = r.plane[1] = plane;
    r.flex[0] = r.flex[1] = flex;
    r.twist[0] = r.twist[1] = 0;
    r.wrist[0] = r.wrist[1] = 0;
    return FreeArms(shape, 3, 2, r).apply(b, 0.5);
  };
  const double reach = P.upper_arm + P.forearm;
  const BodyPose down = hold(0, 0, 0), side = hold(90, 0, 0), ahead = hold(90, 90, 0), folded = hold(0, 0, 90);
  for (int s = 0; s < 2; ++s) {
    const Vec3 sh = b.p[kShoulderR + s], out = s ? left : Vec3(-left);
    CHECK((down.p[kWristR + s] - (sh - reach * up)).norm() < 1e-6);
    CHECK((side.p[kWristR + s] - (sh + reach * out)).norm() < 1e-6);
    CHECK((ahead.p[kWristR + s] - (sh + reach * forward)).norm() < 1e-6);
    // Upper arm hanging, the forearm folded forward at 90 degrees.
    CHECK((folded.p[kWristR + s] - (sh - P.upper_arm * up + P.forearm * forward)).norm() < 1e-6);
  }
}

TEST_CASE("free arms: the simulator moves the arms only, scene.json and the dataset carry the seed", "[sim]") {
  SimSpec s = preset_spec("front-high-static");
  s.motion = "dance";
  s.duration_s = 1;
  s.frame_dancer = true;
  const Simulator plain(s);
  SimSpec f = s;
  f.free_arms_seed = 12345;
  const Simulator freed(f);
  double moved = 0;
  for (double t : {0.0, 0.4, 0.9}) {
    const Label a = plain.label_at(t), b = freed.label_at(t);
    for (int j : {0, 1, 2, 5, 6, 9, 10, 11, 12}) CHECK((a.joints_mm[j] - b.joints_mm[j]).norm() < 1e-6);
    for (int j : {3, 4, 7, 8}) moved = std::max(moved, (a.joints_mm[j] - b.joints_mm[j]).norm());
  }
  CHECK(moved > 100);
  CHECK(nlohmann::json::parse(freed.description_json()).at("free_arms_seed") == 12345);
  CHECK_FALSE(nlohmann::json::parse(plain.description_json()).contains("free_arms_seed"));
  CHECK(spec_from_json(R"({"preset": "front-high-static", "free_arms_seed": 99})", "x.json").free_arms_seed == 99);
  f.arm_offset_s = {0.5, 0};
  CHECK_THROWS_WITH(Simulator(f), Catch::Contains("exclude each other"));
  // The dataset frees a share of the training dancers, from its own stream, never a remixed one.
  int freed_n = 0;
  for (int i = 0; i < 200; ++i) {
    SimSpec m = dataset_member("train", i, 1, 5.0, true, true);
    const SimSpec before = m;
    free_member_arms(m, 1, i, false, 0.0);
    CHECK(m.name == before.name);
    CHECK(m.free_arms_seed == 0);
    free_member_arms(m, 1, i, false, 0.5);
    if (m.free_arms_seed != 0) {
      ++freed_n;
      CHECK(m.name == before.name + "-free");
      CHECK(m.seed == before.seed);
    } else {
      CHECK(m.name == before.name);
    }
    SimSpec remixed = before;
    remix_member_arms(remixed, 1, i, false, 1.0);
    free_member_arms(remixed, 1, i, false, 1.0);
    CHECK(remixed.free_arms_seed == 0);
    CHECK(remixed.name == before.name + "-remix");
  }
  CHECK(freed_n > 70);
  CHECK(freed_n < 130);
  SimSpec m = dataset_member("train", 3, 1, 5.0, true, true);
  CHECK_THROWS_AS(free_member_arms(m, 1, 3, false, 1.5), std::invalid_argument);
}
