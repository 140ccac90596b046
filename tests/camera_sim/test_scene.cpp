// Scene: camera views and orbits, light levels, background and occluders, seeding.
#include <omp.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>

#include "camera/sim/scene.h"

using namespace yelan::camera::sim;

namespace {

Primitive ball(const Vec3& c, double r, float albedo, bool human) {
  Primitive p;
  p.shape = Shape::ellipsoid;
  p.a = c;
  p.axes = Eigen::Matrix3d::Identity() * r;
  p.material.albedo = albedo;
  p.human = human;
  return p;
}

// A stand-in dancer: a torso (not in the mask) with four markers half-buried in it, front
// (-y), back (+y), the dancer's left (+x) and right (-x), each flagged human on its own.
std::vector<Primitive> marked_body(int marker) {
  std::vector<Primitive> body;
  Primitive torso;
  torso.shape = Shape::round_cone;
  torso.a = {0, 0, 300}, torso.b = {0, 0, 1600}, torso.ra = torso.rb = 250;
  torso.material.albedo = 0.3f;
  body.push_back(torso);
  const Vec3 where[4] = {{0, -250, 1000}, {0, 250, 1000}, {250, 0, 1000}, {-250, 0, 1000}};
  body.push_back(ball(where[marker], 120, 0.9f, true));
  return body;
}

int mask_count(const RenderedFrame& f) {
  int n = 0;
  for (auto m : f.mask) n += m;
  return n;
}

double mask_centroid_x(const RenderedFrame& f) {
  double s = 0;
  int n = 0;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x)
      if (f.mask[std::size_t(y) * f.width + x]) s += x, ++n;
  return n ? s / n : -1;
}

Vec3 project(const CameraModel& c, const Vec3& w) {
  const Vec3 p = c.M.leftCols<3>() * w + c.M.col(3);
  return {c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy, p.z()};
}

}  // namespace

TEST_CASE("render.scene cameras: views, orbit and aim") {
  const CameraModel front = view_camera(View::front);
  CHECK(camera_centre(front).isApprox(Vec3(0, -3500, 1200), 1e-9));
  // The aim point (0, 0, 1000) lands on the principal point, 3500 mm / cos(pitch) away.
  const Vec3 aim = project(front, {0, 0, 1000});
  CHECK(aim.x() == Approx(173).margin(1e-9));
  CHECK(aim.y() == Approx(130).margin(1e-9));
  CHECK(aim.z() == Approx(std::hypot(3500.0, 200.0)).epsilon(1e-12));
  // Image right is world +x (the dancer's left) for the front camera; up is up.
  CHECK(project(front, {500, 0, 1000}).x() > 173 + 60);
  CHECK(project(front, {0, 0, 1500}).y() < 130 - 60);
  CHECK(camera_centre(view_camera(View::left)).isApprox(Vec3(3500, 0, 1200), 1e-9));
  CHECK(camera_centre(view_camera(View::right)).isApprox(Vec3(-3500, 0, 1200), 1e-9));
  CHECK(camera_centre(view_camera(View::back)).isApprox(Vec3(0, 3500, 1200), 1e-9));
  // Explicit pitch: 10 deg down from 1200 mm, the optical axis meets z = 1200 - d tan(10).
  const CameraModel o = orbit_camera(30, 10, 5000, 1200, davis346(500));
  CHECK(o.fx == 500);
  CHECK(camera_centre(o).isApprox(Vec3(5000 * std::sin(30 * 3.141592653589793 / 180),
                                       -5000 * std::cos(30 * 3.141592653589793 / 180), 1200),
                                  1e-9));
  CHECK(project(o, {0, 0, 1200 - 5000 * std::tan(10 * 3.141592653589793 / 180)}).y() ==
        Approx(130).margin(1e-6));
  CHECK_THROWS_AS(orbit_camera(0, 0, -1, 1200, davis346()), std::invalid_argument);
  CHECK_THROWS_AS(orbit_camera(0, 95, 3000, 1200, davis346()), std::invalid_argument);
}

TEST_CASE("render.scene views see the dancer's front, back, left and right") {
  const View views[4] = {View::front, View::back, View::left, View::right};
  const int opposite[4] = {1, 0, 3, 2};
  for (int v = 0; v < 4; ++v) {
    SceneConfig cfg;
    cfg.view = views[v];
    Scene scene(cfg);
    RenderedFrame own, far;
    scene.render(0, marked_body(v), own);
    scene.render(0, marked_body(opposite[v]), far);
    INFO(view_name(views[v]));
    CHECK(mask_count(own) > 300);  // the marker on the side this camera faces is seen
    CHECK(mask_count(far) == 0);   // ... and the one on the far side is hidden
    CHECK(mask_centroid_x(own) == Approx(173).margin(3));
  }
  // From the front, the dancer's left marker (+x) is on the image right.
  SceneConfig cfg;
  Scene scene(cfg);
  RenderedFrame f;
  scene.render(0, marked_body(2), f);
  CHECK(mask_centroid_x(f) > 173 + 10);
}

TEST_CASE("render.scene light levels set the intensity scale") {
  const double expect[3] = {255, 60, 20};
  const LightLevel levels[3] = {LightLevel::high, LightLevel::medium, LightLevel::low};
  for (int i = 0; i < 3; ++i) {
    const Lighting l = lighting(levels[i], false);
    CHECK(l.flicker_depth == 0);
    // A white quad facing the key light, seen along the light direction.
    CameraModel cam = davis346();
    cam.M.leftCols<3>().setIdentity();
    l.key_dir.normalized();
    Lighting cl = l;
    cl.key_dir = Vec3(0, 0, -1);
    Primitive q;
    q.shape = Shape::quad;
    q.a = {-500, -500, 2000};
    q.axes.col(0) = Vec3(1000, 0, 0);
    q.axes.col(1) = Vec3(0, 1000, 0);
    q.material.albedo = 1;
    RenderedFrame f;
    render(cam, {q}, cl, 0, f);
    CHECK(f.intensity[130 * 346 + 173] == Approx(expect[i]).epsilon(1e-6));
    // Facing away from the key light: the ambient share only.
    cl.key_dir = Vec3(0, 0, 1);
    render(cam, {q}, cl, 0, f);
    CHECK(f.intensity[130 * 346 + 173] == Approx(expect[i] * l.ambient).epsilon(1e-6));
    const Lighting fl = lighting(levels[i], true);
    CHECK(fl.flicker_depth >= 0.1);
    CHECK(fl.flicker_depth <= 0.3);
    CHECK(fl.flicker_hz == 100);
  }
}

TEST_CASE("render.scene flicker scales the whole frame at 100 Hz") {
  SceneConfig cfg;
  cfg.light = LightLevel::medium;
  cfg.flicker = true;
  Scene scene(cfg);
  RenderedFrame a, b, c;
  const auto body = marked_body(0);
  scene.render(0.0, body, a);     // peak: 1 + m
  scene.render(0.005, body, b);   // trough: 1 - m
  scene.render(0.010, body, c);   // peak again
  const double m = scene.light().flicker_depth;
  REQUIRE(m == Approx(0.2));
  const std::size_t i = 40 * 346 + 40;  // the wall
  REQUIRE(a.intensity[i] > 1);
  CHECK(b.intensity[i] / a.intensity[i] == Approx((1 - m) / (1 + m)).epsilon(1e-5));
  CHECK(c.intensity == a.intensity);
}

TEST_CASE("render.scene background: seeded, static or moving") {
  SceneConfig cfg;
  cfg.seed = 7;
  Scene s1(cfg), s2(cfg);
  RenderedFrame a, b;
  s1.render(0.3, marked_body(0), a);
  s2.render(0.3, marked_body(0), b);
  CHECK(a.intensity == b.intensity);
  CHECK(a.depth_mm == b.depth_mm);
  CHECK(s1.description() == s2.description());
  // Everything is covered by the wall or the floor.
  for (float d : a.depth_mm) REQUIRE(std::isfinite(d));
  cfg.seed = 8;
  Scene s3(cfg);
  s3.render(0.3, marked_body(0), b);
  CHECK(a.intensity != b.intensity);

  // Static wall: the background does not change with time.
  RenderedFrame later;
  s1.render(1.7, marked_body(0), later);
  CHECK(later.intensity == a.intensity);

  // Dynamic: something moves outside the dancer between t = 0 and t = 0.5 s.
  cfg.background = SceneConfig::dynamic;
  Scene dyn(cfg);
  RenderedFrame d0, d1;
  dyn.render(0.0, marked_body(0), d0);
  dyn.render(0.5, marked_body(0), d1);
  int changed = 0;
  for (std::size_t i = 0; i < d0.intensity.size(); ++i)
    changed += !d0.mask[i] && std::fabs(d0.intensity[i] - d1.intensity[i]) > 1;
  CHECK(changed > 200);
  CHECK(mask_count(d0) == mask_count(d1));  // background objects are not in the mask
  std::vector<Primitive> moving;
  dyn.dynamic_primitives(0.0, moving);
  CHECK(moving.size() > 15);
  CHECK(dyn.description().find("dynamic") != std::string::npos);
}

TEST_CASE("render.scene occluders hide part of the dancer") {
  // The whole torso in the mask; count it with and without occluders over a few seconds.
  std::vector<Primitive> body = marked_body(0);
  body[0].human = true;
  SceneConfig cfg;
  cfg.seed = 3;
  Scene open(cfg);
  cfg.occluders = true;
  Scene occl(cfg);
  RenderedFrame f;
  open.render(0, body, f);
  const int full = mask_count(f);
  REQUIRE(full > 3000);
  int least = full, most = 0;
  for (int k = 0; k < 80; ++k) {  // the panel crosses every 3-5 s
    occl.render(0.1 * k, body, f);
    least = std::min(least, mask_count(f));
    most = std::max(most, mask_count(f));
  }
  CHECK(most < full);           // the static box or pillar always covers some of it
  CHECK(least < most - 500);    // and the crossing panel covers more at some time
  CHECK(occl.static_primitives().size() > open.static_primitives().size());
}

TEST_CASE("render.scene one and two threads give identical frames") {
  SceneConfig cfg;
  cfg.background = SceneConfig::dynamic;
  cfg.occluders = true;
  cfg.flicker = true;
  cfg.view = View::left;
  cfg.seed = 11;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  Scene one(cfg);
  RenderedFrame a;
  one.render(0.77, marked_body(2), a);
  omp_set_num_threads(2);
  Scene two(cfg);
  RenderedFrame b;
  two.render(0.77, marked_body(2), b);
  omp_set_num_threads(saved);
  CHECK(a.intensity == b.intensity);
  CHECK(a.mask == b.mask);
  CHECK(a.depth_mm == b.depth_mm);
}

TEST_CASE("render.scene a body edge moving 0.1 px over the wall changes pixels smoothly") {
  SceneConfig cfg;
  cfg.seed = 21;
  Scene scene(cfg);
  const CameraModel& cam = scene.camera();
  // A bright panel in the body plane (y = 0); one step moves it by 0.1 px at 3.5 m.
  const double px_mm = std::hypot(3500.0, 200.0) / cam.fx;
  Primitive p;
  p.shape = Shape::quad;
  p.axes.col(0) = Vec3(400, 0, 0);
  p.axes.col(1) = Vec3(0, 0, 900);
  p.material.albedo = 0.95f;
  p.human = true;
  RenderedFrame prev, cur;
  p.a = Vec3(-200, 0, 600);
  scene.render(0, {p}, prev);
  double worst = 0;
  for (int step = 1; step <= 20; ++step) {
    p.a.x() = -200 + 0.1 * px_mm * step;
    scene.render(0, {p}, cur);
    for (std::size_t i = 0; i < cur.intensity.size(); ++i)
      worst = std::max(worst, double(std::fabs(cur.intensity[i] - prev.intensity[i])));
    std::swap(prev, cur);
  }
  CHECK(worst > 5);            // the edges do move
  CHECK(worst < 0.13 * 255);   // one of 8 sub-pixel rays at a time, never a whole step
}

#include "camera/sim/simulator.h"

TEST_CASE("render.scene camera motion: a still camera stays, pan sweeps about 6 deg, shake trembles, labels follow") {
  SceneConfig c;
  c.seed = 11;
  const Scene still(c);
  CHECK(still.camera_at(1.3).M.isApprox(still.camera().M));
  CHECK(still.camera_image_speed() == 0);
  // The angle between the optical axes at rest and at t.
  const auto axis_angle_deg = [](const CameraModel& a, const CameraModel& b) {
    const Vec3 za = a.M.block<1, 3>(2, 0).transpose(), zb = b.M.block<1, 3>(2, 0).transpose();
    return std::acos(std::clamp(za.dot(zb), -1.0, 1.0)) * 180 / 3.141592653589793;
  };
  c.camera_motion = SceneConfig::pan;
  const Scene pan(c);
  double widest = 0;
  for (double t = 0; t < 8; t += 0.05) widest = std::max(widest, axis_angle_deg(pan.camera(), pan.camera_at(t)));
  CHECK(widest == Approx(6).margin(0.1));
  // The camera turns about its own centre: the centre does not move.
  CHECK((camera_centre(pan.camera_at(2)) - camera_centre(pan.camera())).norm() < 1e-6);
  c.camera_motion = SceneConfig::shake;
  const Scene shake(c);
  double most = 0;
  for (double t = 0; t < 2; t += 0.01) most = std::max(most, axis_angle_deg(shake.camera(), shake.camera_at(t)));
  CHECK(most > 0.2);
  CHECK(most < 1.5);
  CHECK(shake.camera_image_speed() > pan.camera_image_speed());
  // Labels are in the moving camera's frame.
  SimSpec s;
  s.character = "ben";
  s.motion = "dance";
  s.scene = c;
  s.duration_s = 0.2;
  Simulator sim(s);
  const Label l = sim.label_at(0.1);
  SimSpec rest = s;
  rest.scene.camera_motion = SceneConfig::still;
  const Label still_label = Simulator(rest).label_at(0.1);
  CHECK((l.joints_mm[0] - still_label.joints_mm[0]).norm() > 1);  // the tremor moves the head in the camera frame
  CHECK((l.joints_mm[0] - still_label.joints_mm[0]).norm() < 80);
}

TEST_CASE("render.scene sweep: a hand-held camera looks around by degrees, tens of deg/s") {
  SceneConfig c;
  c.seed = 12;
  c.camera_motion = SceneConfig::pan;
  const Scene pan(c);
  c.camera_motion = SceneConfig::sweep;
  const Scene sweep(c), again(c);
  const auto axis_angle_deg = [](const CameraModel& a, const CameraModel& b) {
    const Vec3 za = a.M.block<1, 3>(2, 0).transpose(), zb = b.M.block<1, 3>(2, 0).transpose();
    return std::acos(std::clamp(za.dot(zb), -1.0, 1.0)) * 180 / 3.141592653589793;
  };
  double widest = 0, fastest = 0;
  for (double t = 0; t < 10; t += 0.01) {
    widest = std::max(widest, axis_angle_deg(sweep.camera(), sweep.camera_at(t)));
    fastest = std::max(fastest, axis_angle_deg(sweep.camera_at(t), sweep.camera_at(t + 0.01)) / 0.01);
  }
  CHECK(widest > 2);
  CHECK(widest < 15);
  CHECK(fastest > 5);   // deg/s: pan's 6 deg over 2 s is under 5
  CHECK(fastest < 80);
  CHECK(sweep.camera_image_speed() > 3 * pan.camera_image_speed());
  CHECK(sweep.camera_at(3.7).M == again.camera_at(3.7).M);  // seeded
  CHECK((camera_centre(sweep.camera_at(2)) - camera_centre(sweep.camera())).norm() < 1e-6);
  CHECK(sweep.description().find("camera sweeping") != std::string::npos);
  CHECK(pan.description().find("sweeping") == std::string::npos);
  CHECK(std::string(camera_motion_name(SceneConfig::sweep)) == "sweep");
}

TEST_CASE("render.scene clutter furnishes the room, seeded, and leaves the dancer's spot clear") {
  SceneConfig c;
  c.seed = 21;
  Scene bare(c);
  c.clutter = true;
  Scene room(c), same(c);
  CHECK(room.static_primitives().size() >= bare.static_primitives().size() + 10);
  CHECK(room.description().find("furnished room") != std::string::npos);
  CHECK(bare.description().find("furnished") == std::string::npos);
  RenderedFrame a, b, plain;
  room.render(0.2, marked_body(0), a);
  same.render(0.2, marked_body(0), b);
  bare.render(0.2, marked_body(0), plain);
  CHECK(a.intensity == b.intensity);
  CHECK(a.intensity != plain.intensity);
  // Nothing of the room hides the dancer: the marker shows as much as in the bare room.
  CHECK(mask_count(a) == mask_count(plain));
  CHECK(mask_count(a) > 100);
  // Over many seeds and every view, nothing stands on the spot (1 m around the dancer).
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    c.seed = seed;
    c.view = View(seed % 4);
    const Scene s(c);
    for (const Primitive& p : s.static_primitives()) {
      if (p.shape != Shape::quad || std::fabs(p.axes.col(2).z()) > 0.5) {  // a standing or round thing
        const Vec3 foot = p.shape == Shape::quad ? Vec3(p.a + 0.5 * p.axes.col(0)) : p.a;
        CHECK(Eigen::Vector2d(foot.x(), foot.y()).norm() > 500);
      }
    }
  }
}
