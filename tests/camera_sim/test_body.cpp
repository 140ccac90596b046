// Body, clothing and the cast: geometry covers the skeleton, cloth and hair lag and settle,
// springs stay bounded at any step, texture frames turn with the body, and the cast has the
// spread of shapes, clothes and held-out characters the training split needs.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <set>
#include <stdexcept>

#include <Eigen/Geometry>

#include "camera/sim/body.h"
#include "camera/sim/characters.h"
#include "camera/sim/rng.h"

using namespace yelan::camera::sim;

namespace {

// A standing pose for a body of height H facing -y (its left is +x), feet flat on the
// floor, with the segment proportions motion.cpp uses (Drillis & Contini).
BodyPose standing_pose(double H, bool female = false) {
  BodyPose pose;
  auto at = [&](BodyPoint b, double x, double y, double z) { pose.p[b] = Vec3(x, y, z) * H; };
  at(kPelvis, 0, 0, 0.53);
  at(kChest, 0, 0, 0.66);
  at(kNeck, 0, 0, 0.818);
  at(kHead, 0, 0, 0.935);
  at(kHeadTop, 0, 0, 1.0);
  at(kNose, 0, -0.062, 0.925);
  at(kChin, 0, -0.040, 0.875);
  const double shoulder = (female ? 0.245 : 0.259) / 2, hip = (female ? 0.120 : 0.110) / 2;
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? -1 : 1;  // right is -x
    at(BodyPoint(kShoulderR + side), shoulder * s, 0, 0.818);
    at(BodyPoint(kElbowR + side), (shoulder + 0.01) * s, 0, 0.632);
    at(BodyPoint(kWristR + side), (shoulder + 0.015) * s, 0, 0.486);
    at(BodyPoint(kHandTipR + side), (shoulder + 0.015) * s, 0, 0.378);
    at(BodyPoint(kHipR + side), hip * s, 0, 0.53);
    at(BodyPoint(kKneeR + side), hip * s, 0, 0.285);
    at(BodyPoint(kAnkleR + side), hip * s, 0, 0.039);
    at(BodyPoint(kToeR + side), hip * s, -std::sqrt(0.12 * 0.12 - 0.039 * 0.039), 0);
  }
  return pose;
}

BodyPose moved(BodyPose pose, const Eigen::Matrix3d& R, const Vec3& shift) {
  for (Vec3& q : pose.p) q = R * q + shift;
  return pose;
}

Eigen::Matrix3d yaw(double rad) { return Eigen::AngleAxisd(rad, Vec3::UnitZ()).toRotationMatrix(); }

// How far (mm) x lies outside a solid primitive; 0 inside. Cone shells are not solids.
double outside_by(const Primitive& q, const Vec3& x) {
  if (q.shape == Shape::round_cone) {
    const Vec3 ab = q.b - q.a;
    const double t = std::clamp((x - q.a).dot(ab) / std::max(ab.squaredNorm(), 1e-12), 0.0, 1.0);
    return std::max(0.0, (x - (q.a + t * ab)).norm() - (q.ra + t * (q.rb - q.ra)));
  }
  if (q.shape == Shape::ellipsoid) {
    const double n = (q.axes.inverse() * (x - q.a)).norm();
    return n <= 1 ? 0.0 : (n - 1) * q.axes.colwise().norm().minCoeff();
  }
  return 1e30;
}

double nearest_solid(const std::vector<Primitive>& prims, const Vec3& x) {
  double best = 1e30;
  for (const Primitive& q : prims) best = std::min(best, outside_by(q, x));
  return best;
}

std::vector<Primitive> dress_at_rest(const Character& c, const BodyPose& pose,
                                     std::uint64_t seed = 1) {
  Dresser dresser(c, seed);
  dresser.update(pose, 0.0);
  std::vector<Primitive> prims;
  dresser.primitives(prims);
  return prims;
}

int expected_count(const Character& c) {
  return 24 + (c.hair != Hair::bald) + 3 * (c.hair == Hair::long_hair) + 2 * c.hat +
         (c.clothing != Clothing::tight);
}

bool same_bytes(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), 24) == 0; }

}  // namespace

TEST_CASE("body cast: at least 12 distinct characters spanning shapes and clothes") {
  const auto& cast = characters();
  REQUIRE(cast.size() >= 12);
  std::set<std::string> names;
  std::set<Clothing> clothes, held_out_clothes;
  std::set<Pattern> patterns;
  int held_out = 0, female = 0;
  double lo_h = 1e9, hi_h = 0, lo_g = 1e9, hi_g = 0, darkest = 1, lightest = 0;
  bool hat = false, long_hair = false;
  for (const Character& c : cast) {
    INFO(c.name);
    CHECK(names.insert(c.name).second);
    CHECK(!c.name.empty());
    for (char ch : c.name) CHECK(((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9')));
    CHECK(c.shape.height_mm >= 1500);
    CHECK(c.shape.height_mm <= 1950);
    CHECK(c.shape.girth >= 0.8);
    CHECK(c.shape.girth <= 1.4);
    lo_h = std::min(lo_h, c.shape.height_mm);
    hi_h = std::max(hi_h, c.shape.height_mm);
    lo_g = std::min(lo_g, c.shape.girth);
    hi_g = std::max(hi_g, c.shape.girth);
    female += c.shape.female;
    clothes.insert(c.clothing);
    if (c.test_only) held_out_clothes.insert(c.clothing);
    held_out += c.test_only;
    hat |= c.hat;
    long_hair |= c.hair == Hair::long_hair;
    for (const Material* m : {&c.skin, &c.top, &c.bottom, &c.hair_material}) {
      patterns.insert(m->pattern);
      darkest = std::min({darkest, double(m->albedo), double(m->albedo2)});
      lightest = std::max({lightest, double(m->albedo), double(m->albedo2)});
      CHECK(m->albedo >= 0);
      CHECK(m->albedo <= 1);
    }
  }
  CHECK(held_out == 3);
  CHECK(held_out_clothes.size() == 3);
  CHECK(female >= 4);
  CHECK(int(cast.size()) - female >= 4);
  CHECK(clothes.size() == 5);
  CHECK(patterns.size() == 4);
  CHECK(hat);
  CHECK(long_hair);
  CHECK(lo_h <= 1520);
  CHECK(hi_h >= 1920);
  CHECK(lo_g <= 0.85);
  CHECK(hi_g >= 1.35);
  CHECK(darkest <= 0.05);
  CHECK(lightest >= 0.75);
  // Held-out characters come after the training ones, so a training run can take a prefix.
  bool seen_held_out = false;
  for (const Character& c : cast) {
    if (c.test_only) seen_held_out = true;
    CHECK((c.test_only || !seen_held_out));
  }
}

TEST_CASE("body cast: lookup by name, unknown names list the known ones") {
  CHECK(character_by_name("ana").name == "ana");
  CHECK(character_by_name("kurt").test_only);
  try {
    character_by_name("zed");
    FAIL("no exception for an unknown name");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("'zed'") != std::string::npos);
    CHECK(what.find("ana") != std::string::npos);
    CHECK(what.find("lena") != std::string::npos);
  }
  CHECK_THROWS_AS(character_by_name(""), std::invalid_argument);
  CHECK_THROWS_AS(character_by_name("Ana"), std::invalid_argument);
}

TEST_CASE("body dresser: primitive count per outfit, all human, finite, within the bound") {
  for (const Character& c : characters()) {
    INFO(c.name);
    const BodyPose pose = standing_pose(c.shape.height_mm, c.shape.female);
    const auto prims = dress_at_rest(c, pose);
    CHECK(int(prims.size()) == expected_count(c));
    CHECK(int(prims.size()) <= Dresser::kMaxPrimitives);
    int shells = 0;
    for (const Primitive& q : prims) {
      CHECK(q.human);
      CHECK(q.a.allFinite());
      CHECK(q.b.allFinite());
      CHECK(q.axes.allFinite());
      CHECK(std::abs(q.material.u_axis.norm() - 1) < 1e-9);
      CHECK(std::abs(q.material.v_axis.norm() - 1) < 1e-9);
      CHECK(std::abs(q.material.u_axis.dot(q.material.v_axis)) < 1e-9);
      if (q.shape == Shape::round_cone) {
        CHECK(q.ra > 5);
        CHECK(q.rb > 5);
      }
      if (q.shape == Shape::ellipsoid) CHECK(std::abs(q.axes.determinant()) > 1e3);
      if (q.shape == Shape::cone_shell) {
        ++shells;
        CHECK(q.rb >= q.ra);  // hangs open at rest
        CHECK(q.b.z() < q.a.z());
      }
    }
    CHECK(shells == (c.clothing != Clothing::tight));
    // The body stays within its standing height (hat excepted) and above the floor.
    double top = 0;
    for (int i = 0; i < 22; ++i) {
      const Primitive& q = prims[i];
      if (q.shape == Shape::ellipsoid)
        top = std::max(top, q.a.z() + q.axes.row(2).norm());
      else
        top = std::max({top, q.a.z() + q.ra, q.b.z() + q.rb});
    }
    CHECK(top <= c.shape.height_mm * 1.01);
    CHECK(top >= c.shape.height_mm * 0.98);
  }
}

TEST_CASE("body dresser: every DHP19 joint and the bones between them lie inside the flesh") {
  const std::pair<BodyPoint, BodyPoint> bones[] = {
      {kPelvis, kChest},     {kChest, kNeck},       {kNeck, kHead},        {kShoulderR, kElbowR},
      {kShoulderL, kElbowL}, {kElbowR, kWristR},    {kElbowL, kWristL},    {kHipR, kKneeR},
      {kHipL, kKneeL},       {kKneeR, kAnkleR},     {kKneeL, kAnkleL},     {kNeck, kShoulderR},
      {kNeck, kShoulderL},   {kPelvis, kHipR},      {kPelvis, kHipL}};
  Rng rng(7, 1);
  for (const Character& c : characters()) {
    INFO(c.name);
    const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
    // The rest pose, and the same turned and moved, with every point jittered by 15 mm.
    for (int trial = 0; trial < 4; ++trial) {
      BodyPose pose = moved(rest, yaw(trial * 1.3), Vec3(trial * 300.0, -trial * 200.0, 0));
      if (trial > 0)
        for (Vec3& q : pose.p) q += 15.0 * Vec3(rng.normal(), rng.normal(), rng.normal());
      const auto prims = dress_at_rest(c, pose);
      for (int j = 0; j < kJointCount; ++j) {
        INFO("joint " << j << " trial " << trial);
        CHECK(nearest_solid(prims, pose.p[kDhp19Points[j]]) <= 1.0);
      }
      for (const auto& [from, to] : bones)
        for (double s = 0.1; s < 1.0; s += 0.2) {
          INFO("bone " << from << "-" << to << " at " << s);
          CHECK(nearest_solid(prims, pose.p[from] + s * (pose.p[to] - pose.p[from])) <= 1.0);
        }
    }
  }
}

TEST_CASE("body dresser: hips wider than shoulders for women, chest wider for men") {
  Character a = character_by_name("ben"), b = a;
  b.shape.female = true;
  const double H = a.shape.height_mm;
  const BodyPose pose = standing_pose(H);
  // Slots 3 and 7 are the chest and pelvis ellipsoids; column 0 is the lateral semi-axis.
  auto hips_over_chest = [](const std::vector<Primitive>& prims) {
    REQUIRE(prims[3].shape == Shape::ellipsoid);
    REQUIRE(prims[7].shape == Shape::ellipsoid);
    return prims[7].axes.col(0).norm() / prims[3].axes.col(0).norm();
  };
  const auto male = dress_at_rest(a, pose);
  const double m_ratio = hips_over_chest(male);
  // Flesh alone (same skeleton): by hand, (0.055 + 0.052) / (0.34 * 0.259) over
  // (0.055 + 0.045) / (0.36 * 0.259) = 1.1330.
  CHECK(hips_over_chest(dress_at_rest(b, pose)) / m_ratio == Approx(1.1330).epsilon(0.001));
  // With each sex's own skeleton (motion.cpp's shoulder and hip spacing) the gap widens.
  CHECK(hips_over_chest(dress_at_rest(b, standing_pose(H, true))) > m_ratio * 1.2);
  // Girth widens the flesh around the same bones.
  Character wide = a;
  wide.shape.girth = 1.4;
  const auto w = dress_at_rest(wide, pose);
  CHECK(w[16].ra == Approx(male[16].ra * 1.4));  // right thigh
  CHECK(w[4].axes.col(1).norm() == Approx(male[4].axes.col(1).norm() * 1.4));  // belly depth
}

TEST_CASE("body dresser: texture frames and geometry turn and move with the body") {
  const Eigen::Matrix3d R = yaw(1.1);
  const Vec3 shift(250, -400, 0);
  for (const char* name : {"ana", "carl", "gus", "kurt"}) {
    INFO(name);
    if (std::string(name) == "kurt") REQUIRE(character_by_name(name).stripes_along);
    const Character& c = character_by_name(name);
    const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
    const auto before = dress_at_rest(c, rest), after = dress_at_rest(c, moved(rest, R, shift));
    REQUIRE(before.size() == after.size());
    for (size_t i = 0; i < before.size(); ++i) {
      INFO("primitive " << i);
      const Primitive &p = before[i], &q = after[i];
      CHECK((q.a - (R * p.a + shift)).norm() < 1e-6);
      if (p.shape == Shape::ellipsoid)
        CHECK((q.axes - R * p.axes).norm() < 1e-6);
      else
        CHECK((q.b - (R * p.b + shift)).norm() < 1e-6);
      CHECK((q.material.origin - (R * p.material.origin + shift)).norm() < 1e-6);
      CHECK((q.material.u_axis - R * p.material.u_axis).norm() < 1e-9);
      CHECK((q.material.v_axis - R * p.material.v_axis).norm() < 1e-9);
    }
    // The chest's stripes vary along u: up the spine (hoops around the torso), or across
    // the shoulders for characters whose stripes run along the body.
    const Vec3 spine = Vec3::UnitZ(), shoulders = R * Vec3::UnitX();
    CHECK((after[3].material.u_axis - (c.stripes_along ? shoulders : spine)).norm() < 1e-9);
    CHECK((after[3].material.v_axis - (c.stripes_along ? spine : shoulders)).norm() < 1e-9);
    // A thigh's hoops go round the leg: u down the bone.
    const Vec3 thigh = (after[16].b - after[16].a).normalized();
    CHECK((c.stripes_along ? after[16].material.v_axis : after[16].material.u_axis)
              .dot(thigh) == Approx(1.0));
  }
}

TEST_CASE("body dresser: the same seed gives identical primitives, another seed other prints") {
  const Character& c = character_by_name("lena");
  const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
  auto run = [&](std::uint64_t seed) {
    Dresser d(c, seed);
    std::vector<Primitive> prims;
    for (int i = 0; i <= 700; ++i) {
      const double t = i * 1e-3;
      d.update(moved(rest, yaw(3.0 * t), Vec3(400 * t, 0, 20 * std::sin(20 * t))), t);
    }
    d.primitives(prims);
    return prims;
  };
  const auto a = run(42), b = run(42), other = run(43);
  REQUIRE(a.size() == b.size());
  bool prints_differ = false, springs_differ = false;
  for (size_t i = 0; i < a.size(); ++i) {
    CHECK(same_bytes(a[i].a, b[i].a));
    CHECK(same_bytes(a[i].b, b[i].b));
    CHECK(a[i].ra == b[i].ra);
    CHECK(a[i].rb == b[i].rb);
    CHECK(a[i].material.print_seed == b[i].material.print_seed);
    CHECK(same_bytes(a[i].material.u_axis, b[i].material.u_axis));
    prints_differ |= a[i].material.print_seed != other[i].material.print_seed;
    springs_differ |= !same_bytes(a[i].b, other[i].b);
  }
  CHECK(prints_differ);
  CHECK(springs_differ);  // spring constants vary by seed, so the swinging hem differs
}

TEST_CASE("body springs: a dress hem lags a 200 mm sideways jump, then settles") {
  const Character& c = character_by_name("ana");
  const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
  const BodyPose jumped = moved(rest, Eigen::Matrix3d::Identity(), Vec3(200, 0, 0));
  for (double dt : {1e-3, 1e-4, 20e-3}) {
    INFO("dt " << dt);
    Dresser d(c, 5);
    d.update(rest, 0.0);
    REQUIRE(d.has_hem());
    const Vec3 start = d.hem_centre();
    d.update(jumped, dt);
    const Vec3 goal = d.hem_rest_centre();
    CHECK((goal - start - Vec3(200, 0, 0)).norm() < 1e-9);
    double prev = 0, peak = 0, at_50ms = -1;
    bool smooth = true;
    const int steps = int(std::lround(2.0 / dt));
    for (int i = 2; i <= steps; ++i) {
      d.update(jumped, i * dt);
      const double shift = d.hem_centre().x() - start.x();
      smooth &= std::abs(shift - prev) <= 2500 * dt + 1e-9;  // never faster than 2.5 m/s
      prev = shift;
      peak = std::max(peak, shift);
      if (at_50ms < 0 && i * dt >= 0.05 - 1e-12) at_50ms = shift;
      if (std::abs(i * dt - 1.0) < dt / 2) CHECK((d.hem_centre() - goal).norm() < 15);
    }
    CHECK(smooth);
    CHECK(at_50ms > 2);     // it has started to move
    // but lags well behind the body (a 20 ms step turns the jump into a 10 m/s move, of
    // which the damping follows up to 4 m/s, so the hem starts a little faster)
    CHECK(at_50ms < (dt < 5e-3 ? 40 : 60));
    CHECK(peak < 200 + 8);  // overshoot under 4 %
    CHECK((d.hem_centre() - goal).norm() < 5);
    CHECK(std::abs(d.hem_radius() - [&] {
            Dresser fresh(c, 5);
            fresh.update(jumped, 0.0);
            return fresh.hem_radius();
          }()) < 0.5);
  }
}

TEST_CASE("body springs: long hair trails a head turn and comes back to rest") {
  const Character& c = character_by_name("kurt");
  const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
  Dresser d(c, 3);
  d.update(rest, 0.0);
  REQUIRE(d.has_long_hair());
  const Vec3 tip0 = d.hair_tip();
  // Walk +x at 1.5 m/s: once the start's swing dies down, steady motion carries the hair
  // along without trailing (damping acts on velocity relative to the head).
  const double dt = 1e-3;
  for (int i = 1; i <= 1500; ++i)
    d.update(moved(rest, Eigen::Matrix3d::Identity(), Vec3(1.5 * i, 0, 0)), i * dt);
  CHECK((d.hair_tip() - (tip0 + Vec3(2250, 0, 0))).norm() < 5);
  // Stop dead: the hair swings forward past the head, then settles.
  const BodyPose stopped = moved(rest, Eigen::Matrix3d::Identity(), Vec3(2250, 0, 0));
  double ahead = 0;
  for (int i = 1501; i <= 4000; ++i) {
    d.update(stopped, i * dt);
    ahead = std::max(ahead, d.hair_tip().x() - (tip0.x() + 2250));
  }
  CHECK(ahead > 20);
  CHECK((d.hair_tip() - (tip0 + Vec3(2250, 0, 0))).norm() < 3);
}

TEST_CASE("body springs: a spin flares the skirt out and up, stopping lets it fall back") {
  const Character& c = character_by_name("dana");
  const BodyPose rest = standing_pose(c.shape.height_mm, c.shape.female);
  Dresser d(c, 9);
  d.update(rest, 0.0);
  const double r0 = d.hem_radius(), z0 = d.hem_centre().z();
  const double w = 2 * M_PI * 1.5;  // 1.5 turns a second
  const double dt = 1e-3;
  for (int i = 1; i <= 2000; ++i) d.update(moved(rest, yaw(w * i * dt), Vec3::Zero()), i * dt);
  CHECK(d.hem_radius() > r0 * 1.5);
  CHECK(d.hem_centre().z() > z0 + 50);
  const BodyPose still = moved(rest, yaw(w * 2.0), Vec3::Zero());
  for (int i = 2001; i <= 4500; ++i) d.update(still, i * dt);
  CHECK(std::abs(d.hem_radius() - r0) < 2);
  CHECK(std::abs(d.hem_centre().z() - z0) < 2);
}

TEST_CASE("body springs: random pose jitter at 0.1 ms and 20 ms steps stays bounded") {
  for (const char* name : {"ana", "fay", "gus", "dana"}) {
    const Character& c = character_by_name(name);
    const double H = c.shape.height_mm;
    const BodyPose rest = standing_pose(H);
    for (double dt : {1e-4, 20e-3}) {
      INFO(name << " dt " << dt);
      Dresser d(c, 11);
      Rng rng(11, std::uint64_t(dt * 1e6));
      std::vector<Primitive> prims;
      prims.reserve(Dresser::kMaxPrimitives);
      const int steps = int(std::lround((dt < 1e-3 ? 0.5 : 5.0) / dt));  // 5000 or 250
      double worst_hem = 0, worst_hair = 0;
      bool finite = true;
      for (int i = 0; i < steps; ++i) {
        BodyPose pose = moved(rest, yaw(rng.uniform(-0.3, 0.3)), Vec3::Zero());
        for (Vec3& q : pose.p) q += 40.0 * Vec3(rng.normal(), rng.normal(), rng.normal());
        d.update(pose, i * dt);
        if (d.has_hem()) worst_hem = std::max(worst_hem, (d.hem_centre() - pose.p[kPelvis]).norm());
        if (d.has_long_hair())
          worst_hair = std::max(worst_hair, (d.hair_tip() - pose.p[kHead]).norm());
        if (i % 97 == 0) {
          prims.clear();
          d.primitives(prims);
          for (const Primitive& q : prims)
            finite &= q.a.allFinite() && q.b.allFinite() && std::isfinite(q.rb) &&
                      q.rb < 0.5 * H;
        }
      }
      CHECK(finite);
      CHECK(worst_hem < 0.55 * H);   // the hem never leaves its waistband's reach
      CHECK(worst_hair < 0.35 * H);  // nor the hair its head
    }
  }
}

TEST_CASE("body dresser: absurd shapes and non-finite poses are refused, state kept") {
  Character c = character_by_name("dana");
  c.shape.height_mm = std::nan("");
  CHECK_THROWS_AS(Dresser(c, 1), std::invalid_argument);
  c.shape.height_mm = 12000;
  CHECK_THROWS_WITH(Dresser(c, 1), Catch::Contains("'dana'") && Catch::Contains("height_mm"));
  c.shape.height_mm = 1550;
  c.shape.girth = 0;
  CHECK_THROWS_AS(Dresser(c, 1), std::invalid_argument);

  const Character& ok = character_by_name("dana");
  const BodyPose rest = standing_pose(ok.shape.height_mm, true);
  Dresser d(ok, 1);
  d.update(rest, 0.0);
  d.update(moved(rest, Eigen::Matrix3d::Identity(), Vec3(50, 0, 0)), 0.01);
  const Vec3 hem = d.hem_centre();
  BodyPose bad = rest;
  bad.p[kKneeL].y() = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH(d.update(bad, 0.02), Catch::Contains("body point 18"));
  CHECK_THROWS_AS(d.update(rest, std::nan("")), std::invalid_argument);
  CHECK(same_bytes(d.hem_centre(), hem));
  d.update(rest, 0.02);
  CHECK(d.hem_centre().allFinite());
}

TEST_CASE("body front cues: a dark brow band on the face and a contrasting print on the chest, in front only") {
  for (const Character& c : characters()) {
    INFO(c.name);
    const BodyPose pose = standing_pose(c.shape.height_mm, c.shape.female);
    const auto prims = dress_at_rest(c, pose);
    REQUIRE(prims.size() >= 2);
    const Primitive& brows = prims[prims.size() - 2];
    const Primitive& print = prims.back();
    // The body faces -y at rest: both cues sit in front of the head and the chest.
    CHECK(brows.a.y() < pose.p[kHead].y() - 40);
    CHECK(print.a.y() < pose.p[kChest].y() - 40);
    CHECK(brows.material.albedo < 0.1f);
    CHECK(std::abs(print.material.albedo - c.top.albedo) > 0.3f);
  }
}

TEST_CASE("body front cues scale with front_print: 0 drops both, 2 grows the print down the chest") {
  Character c = character_by_name("ana");
  const BodyPose pose = standing_pose(c.shape.height_mm, c.shape.female);
  const auto one = dress_at_rest(c, pose);
  c.front_print = 0;
  const auto none = dress_at_rest(c, pose);
  REQUIRE(none.size() + 2 == one.size());
  for (std::size_t i = 0; i < none.size(); ++i) CHECK(none[i].a == one[i].a);
  c.front_print = 2;
  const auto two = dress_at_rest(c, pose);
  REQUIRE(two.size() == one.size());
  const Primitive &p1 = one.back(), &p2 = two.back();
  const double lat1 = p1.axes.col(0).norm(), up1 = p1.axes.col(2).norm();
  const double lat2 = p2.axes.col(0).norm(), up2 = p2.axes.col(2).norm();
  CHECK(lat2 == Approx(1.8 * lat1));
  CHECK(up2 == Approx(1.55 * up1));
  // Its top edge stays where it was (below the collar); it still sits in front of the chest.
  CHECK((p2.a + p2.axes.col(2) - (p1.a + p1.axes.col(2))).norm() < 1e-6);
  CHECK(p2.a.y() < pose.p[kChest].y() - 40);
  CHECK(two[two.size() - 2].axes.col(2).norm() == Approx(2 * one[one.size() - 2].axes.col(2).norm()));
}
