// Renderer: intersections, projection, shading, occlusion, anti-aliasing, threads.
#include <omp.h>

#include <catch2/catch.hpp>
#include <cmath>

#include "camera/sim/render.h"

using namespace yelan::camera::sim;

namespace {

// World frame = camera frame (OpenCV): the camera sits at the origin looking along +z.
CameraModel identity_camera() {
  CameraModel c;
  c.M.leftCols<3>().setIdentity();
  return c;
}

Primitive sphere(const Vec3& c, double r, float albedo = 0.8f, bool human = true) {
  Primitive p;
  p.shape = Shape::ellipsoid;
  p.a = c;
  p.axes = Eigen::Matrix3d::Identity() * r;
  p.material.albedo = albedo;
  p.human = human;
  return p;
}

Primitive quad(const Vec3& corner, const Vec3& e0, const Vec3& e1, float albedo = 0.5f) {
  Primitive p;
  p.shape = Shape::quad;
  p.a = corner;
  p.axes.col(0) = e0;
  p.axes.col(1) = e1;
  p.material.albedo = albedo;
  return p;
}

Lighting flat_light(double level = 255, double ambient = 0.3) {
  Lighting l;
  l.level = level;
  l.ambient = ambient;
  l.key_dir = Vec3(0, 0, -1);  // from the camera's side
  return l;
}

std::size_t at(const RenderedFrame& f, int x, int y) { return std::size_t(y) * f.width + x; }

int mask_count(const RenderedFrame& f) {
  int n = 0;
  for (auto m : f.mask) n += m;
  return n;
}

}  // namespace

TEST_CASE("render.sphere projects to the pinhole position and radius") {
  const CameraModel cam = identity_camera();
  RenderedFrame f;
  render(cam, {sphere({0, 0, 3000}, 200)}, flat_light(), 0, f);
  REQUIRE(f.width == 346);
  REQUIRE(f.height == 260);
  // Silhouette radius of a sphere on the axis: f r / sqrt(Z^2 - r^2) = 32.405 px.
  const double rho = 485 * 200 / std::sqrt(3000.0 * 3000 - 200 * 200);
  REQUIRE(rho == Approx(32.405).epsilon(1e-4));
  CHECK(f.mask[at(f, 173 + 32, 130)] == 1);
  CHECK(f.mask[at(f, 173 - 32, 130)] == 1);
  CHECK(f.mask[at(f, 173, 130 + 32)] == 1);
  CHECK(f.mask[at(f, 173 + 33, 130)] == 0);
  CHECK(f.mask[at(f, 173 - 33, 130)] == 0);
  CHECK(f.mask[at(f, 173, 130 - 33)] == 0);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(2800).margin(1e-3));
  CHECK(std::isinf(f.depth_mm[at(f, 0, 0)]));
  CHECK(f.intensity[at(f, 0, 0)] == 0.f);

  // Off axis: (500, -300, 4000) projects to (173 + 485*500/4000, 130 - 485*300/4000).
  render(cam, {sphere({500, -300, 4000}, 150)}, flat_light(), 0, f);
  double sx = 0, sy = 0;
  int n = 0;
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x)
      if (f.mask[at(f, x, y)]) sx += x, sy += y, ++n;
  REQUIRE(n > 0);
  CHECK(sx / n == Approx(233.625).margin(0.3));
  CHECK(sy / n == Approx(93.625).margin(0.3));
}

TEST_CASE("render.mask area equals the projected area") {
  const CameraModel cam = identity_camera();
  RenderedFrame f;
  render(cam, {sphere({0, 0, 3000}, 400)}, flat_light(), 0, f);
  const double rho = 485 * 400 / std::sqrt(3000.0 * 3000 - 400 * 400);
  CHECK(mask_count(f) == Approx(3.141592653589793 * rho * rho).epsilon(0.02));

  // A 1000 x 600 mm quad facing the camera at 5 m covers 97 x 58.2 px.
  Primitive q = quad({-500, -300, 5000}, {1000, 0, 0}, {0, 600, 0});
  q.human = true;
  render(cam, {q}, flat_light(), 0, f);
  CHECK(mask_count(f) == Approx(97.0 * 58.2).epsilon(0.03));
}

TEST_CASE("render.lambertian shading by hand") {
  const CameraModel cam = identity_camera();
  Lighting l = flat_light(255, 0.3);
  l.key_dir = Vec3(0.3, -0.4, -1);  // towards the light; the centre normal is (0, 0, -1)
  RenderedFrame f;
  render(cam, {sphere({0, 0, 3000}, 200, 0.8f)}, l, 0, f);
  const double cosl = 1 / std::sqrt(0.09 + 0.16 + 1);
  CHECK(f.intensity[at(f, 173, 130)] == Approx(0.8 * 255 * (0.3 + 0.7 * cosl)).epsilon(1e-5));
  // Light from behind the sphere: only ambient reaches the visible cap.
  l.key_dir = Vec3(0, 0, 1);
  render(cam, {sphere({0, 0, 3000}, 200, 0.8f)}, l, 0, f);
  CHECK(f.intensity[at(f, 173, 130)] == Approx(0.8 * 255 * 0.3).epsilon(1e-5));
  // Quads are two-sided: seen from either side the camera-facing normal is shaded.
  l.key_dir = Vec3(0, 0, -1);
  render(cam, {quad({-500, -500, 2000}, {1000, 0, 0}, {0, 1000, 0}, 0.6f)}, l, 0, f);
  CHECK(f.intensity[at(f, 173, 130)] == Approx(0.6 * 255).epsilon(1e-5));
  render(cam, {quad({-500, -500, 2000}, {0, 1000, 0}, {1000, 0, 0}, 0.6f)}, l, 0, f);
  CHECK(f.intensity[at(f, 173, 130)] == Approx(0.6 * 255).epsilon(1e-5));
}

TEST_CASE("render.occlusion by a quad in front clears the mask") {
  const CameraModel cam = identity_camera();
  // Body sphere at 3 m; a non-human quad at 2 m covers the image left of x = 173.
  Primitive wall = quad({-2000, -2000, 2000}, {2000, 0, 0}, {0, 4000, 0}, 0.2f);
  RenderedFrame f;
  render(cam, {sphere({0, 0, 3000}, 400), wall}, flat_light(), 0, f);
  CHECK(f.mask[at(f, 150, 130)] == 0);
  CHECK(f.depth_mm[at(f, 150, 130)] == Approx(2000).margin(1e-3));
  CHECK(f.mask[at(f, 190, 130)] == 1);
  CHECK(f.depth_mm[at(f, 190, 130)] > 2600);
  // The order of the list does not matter.
  RenderedFrame g;
  render(cam, {wall, sphere({0, 0, 3000}, 400)}, flat_light(), 0, g);
  CHECK(g.mask == f.mask);
  CHECK(g.depth_mm == f.depth_mm);
}

TEST_CASE("render.round cone hits by hand") {
  const CameraModel cam = identity_camera();
  RenderedFrame f;
  Primitive rc;
  rc.shape = Shape::round_cone;
  rc.human = true;
  // Axis along the view: the centre ray meets the near sphere (ra = 300) at z = 2700.
  rc.a = {0, 0, 3000}, rc.b = {0, 0, 4000}, rc.ra = 300, rc.rb = 100;
  render(cam, {rc}, flat_light(), 0, f);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(2700).margin(1e-3));
  // Reversed: the small sphere is near, but the big one's cone side is seen around it.
  rc.a = {0, 0, 4000}, rc.b = {0, 0, 3000}, rc.ra = 300, rc.rb = 100;
  render(cam, {rc}, flat_light(), 0, f);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(2900).margin(1e-3));
  // Across the view: a = (-400,0,3000) ra 200, b = (400,0,3000) rb 100. At the middle
  // (h = 400) the side line rho cos(phi) + h sin(phi) = ra, sin(phi) = 100/800, gives
  // rho = 150 / cos(phi) = 151.186, so the centre ray hits z = 3000 - 151.186.
  rc.a = {-400, 0, 3000}, rc.b = {400, 0, 3000}, rc.ra = 200, rc.rb = 100;
  render(cam, {rc}, flat_light(), 0, f);
  const double s = 100.0 / 800, rho = 150 / std::sqrt(1 - s * s);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(3000 - rho).margin(1e-3));
  // The ray through x = -400 mm at the end: the tangent point is at h = ra sin(phi) = 25,
  // so x = -400 lies on sphere a: z = 3000 - 200.
  const int xa = int(std::lround(173 - 485 * 400.0 / 2800));  // pixel near x=-400 at z~2800
  CHECK(f.mask[at(f, xa, 130)] == 1);
  // One sphere inside the other: just the larger sphere.
  rc.a = {0, 0, 3000}, rc.b = {0, 0, 3050}, rc.ra = 100, rc.rb = 300;
  render(cam, {rc}, flat_light(), 0, f);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(2750).margin(1e-3));
}

TEST_CASE("render.cone shell is open and two-sided") {
  const CameraModel cam = identity_camera();
  RenderedFrame f;
  Primitive sh;
  sh.shape = Shape::cone_shell;
  sh.human = true;
  // Axis along the view: the centre ray passes through the open ends.
  sh.a = {0, 0, 3000}, sh.b = {0, 0, 4000}, sh.ra = 500, sh.rb = 300;
  render(cam, {sh}, flat_light(), 0, f);
  CHECK(std::isinf(f.depth_mm[at(f, 173, 130)]));
  CHECK(f.mask[at(f, 173, 130)] == 0);
  // An off-axis ray x = s z enters the wide open end and meets the inside wall where the
  // radius 1100 - 0.2 z equals s z: z = 1100 / (s + 0.2).
  const double sx = 48.0 / 485;
  CHECK(f.depth_mm[at(f, 173 + 48, 130)] == Approx(1100 / (sx + 0.2)).margin(1e-2));
  CHECK(f.mask[at(f, 173 + 48, 130)] == 1);
  // Across the view: the centre ray hits the near side at z = 3000 - r(middle) = 2600.
  sh.a = {-500, 0, 3000}, sh.b = {500, 0, 3000}, sh.ra = 500, sh.rb = 300;
  render(cam, {sh}, flat_light(), 0, f);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(2600).margin(1e-3));
}

TEST_CASE("render.stripes moved by 0.1 px change intensity smoothly") {
  const CameraModel cam = identity_camera();
  const Lighting l = flat_light(255, 0.3);
  // Stripes of period 20 mm at 3 m are 3.2 px: without filtering they alias into flicker.
  Primitive q = quad({-1500, -1000, 3000}, {3000, 0, 0}, {0, 2000, 0}, 0.9f);
  q.material.albedo2 = 0.1f;
  q.material.pattern = Pattern::stripes;
  q.material.period_mm = 20;
  q.material.u_axis = Vec3(1, 0.3, 0).normalized();
  const double contrast = 0.8 * 255;
  const double px_mm = 3000.0 / 485;  // one pixel at 3 m
  RenderedFrame prev, cur;
  render(cam, {q}, l, 0, prev);
  double worst = 0;
  for (int step = 1; step <= 30; ++step) {
    q.material.origin = Vec3(0.1 * px_mm * step, 0, 0);
    render(cam, {q}, l, 0, cur);
    for (int y = 20; y < 240; ++y)
      for (int x = 20; x < 326; ++x)
        worst = std::max(worst, double(std::fabs(cur.intensity[at(cur, x, y)] -
                                                 prev.intensity[at(prev, x, y)])));
    std::swap(prev, cur);
  }
  CHECK(worst > 0.01 * contrast);   // the pattern does move
  CHECK(worst < 0.13 * contrast);   // ... never by a whole step

  // A plain silhouette edge moved by 0.1 px: boundary pixels are supersampled with 8
  // n-rooks rays, so one step flips at most one of them.
  Primitive e = quad({0, -1000, 3000}, {1500, 0, 0}, {0, 2000, 0}, 1.0f);
  render(cam, {e}, l, 0, prev);
  worst = 0;
  for (int step = 1; step <= 20; ++step) {
    e.a.x() = 0.1 * px_mm * step;
    render(cam, {e}, l, 0, cur);
    for (std::size_t i = 0; i < cur.intensity.size(); ++i)
      worst = std::max(worst, double(std::fabs(cur.intensity[i] - prev.intensity[i])));
    std::swap(prev, cur);
  }
  CHECK(worst > 0.05 * 255);
  CHECK(worst <= 0.126 * 255);
}

TEST_CASE("render.checks and print patterns average to their mean far away") {
  const CameraModel cam = identity_camera();
  const Lighting l = flat_light(100, 1.0);  // ambient only: intensity = 100 * albedo
  for (Pattern pat : {Pattern::checks, Pattern::print}) {
    Primitive q = quad({-6000, -4000, 12000}, {12000, 0, 0}, {0, 8000, 0}, 1.0f);
    q.material.albedo2 = 0.0f;
    q.material.pattern = pat;
    q.material.period_mm = 8;  // far below one pixel (25 mm at 12 m)
    q.material.u_axis = Vec3::UnitX();
    q.material.v_axis = Vec3::UnitY();
    q.material.print_seed = 42;
    RenderedFrame f;
    render(cam, {q}, l, 0, f);
    double lo = 1e9, hi = -1e9;
    for (int y = 10; y < 250; ++y)
      for (int x = 10; x < 336; ++x) {
        lo = std::min(lo, double(f.intensity[at(f, x, y)]));
        hi = std::max(hi, double(f.intensity[at(f, x, y)]));
      }
    CHECK(hi - lo < 1.0);  // no moire: a uniform grey
    if (pat == Pattern::checks) CHECK(lo == Approx(50).margin(1.0));
  }
}

TEST_CASE("render.flicker modulates at 100 Hz") {
  const CameraModel cam = identity_camera();
  Lighting l = flat_light(200, 0.3);
  l.flicker_depth = 0.2;
  l.flicker_hz = 100;
  const std::vector<Primitive> prims = {quad({-500, -500, 2000}, {1000, 0, 0}, {0, 1000, 0}, 1.0f)};
  auto value = [&](double t) {
    RenderedFrame f;
    render(cam, prims, l, t, f);
    return double(f.intensity[at(f, 173, 130)]);
  };
  CHECK(value(0) == Approx(200 * 1.2).epsilon(1e-5));
  CHECK(value(0.0025) == Approx(200).epsilon(1e-5));
  CHECK(value(0.005) == Approx(200 * 0.8).epsilon(1e-5));
  CHECK(value(0.01) == Approx(200 * 1.2).epsilon(1e-5));
  CHECK(value(0.0123) == Approx(value(0.0023)).epsilon(1e-5));
}

TEST_CASE("render.static layer plus moving primitives matches one full render") {
  const CameraModel cam = identity_camera();
  const Lighting l = flat_light(255, 0.3);
  Primitive back = quad({-3000, -3000, 5000}, {6000, 0, 0}, {0, 6000, 0}, 0.6f);
  back.material.pattern = Pattern::print;
  back.material.period_mm = 150;
  back.material.albedo2 = 0.2f;
  const Primitive pillar = [] {
    Primitive p;
    p.shape = Shape::round_cone;
    p.a = {-300, -2000, 2500}, p.b = {-300, 2000, 2500}, p.ra = p.rb = 120;
    return p;
  }();
  const std::vector<Primitive> stat = {back, pillar};
  Renderer r;
  r.set_static(cam, stat, l);
  for (double t : {0.0, 0.1, 0.2}) {
    std::vector<Primitive> dyn = {sphere({-200 + 1000 * t, 50, 3000}, 250)};
    Primitive arm;
    arm.shape = Shape::round_cone;
    arm.a = {-400, 300, 3100}, arm.b = {100 + 500 * t, 500, 2900}, arm.ra = 60, arm.rb = 40;
    arm.human = true;
    dyn.push_back(arm);
    RenderedFrame inc, full;
    r.render(t, dyn, inc);
    std::vector<Primitive> all = stat;
    all.insert(all.end(), dyn.begin(), dyn.end());
    render(cam, all, l, t, full);
    REQUIRE(inc.intensity.size() == full.intensity.size());
    // Boundary pixels over a flat part of the cached layer take the layer's pixel average
    // for the rays that miss the moving primitives, the full render shades those rays one
    // by one: the same up to the texture's variation inside one pixel.
    int differ = 0;
    double worst = 0;
    for (std::size_t i = 0; i < inc.intensity.size(); ++i) {
      const double d = std::fabs(inc.intensity[i] - full.intensity[i]);
      differ += d > 1e-3;
      worst = std::max(worst, d);
    }
    CHECK(differ < 150);
    CHECK(worst < 0.06 * 255);
    CHECK(inc.mask == full.mask);
    CHECK(inc.depth_mm == full.depth_mm);
    CHECK(mask_count(inc) > 1000);
  }
}

TEST_CASE("render.one and two threads give identical frames") {
  const CameraModel cam = identity_camera();
  Lighting l = flat_light(255, 0.3);
  l.key_dir = Vec3(0.5, -0.5, -0.7);
  std::vector<Primitive> prims;
  for (int i = 0; i < 25; ++i) {
    Primitive p;
    p.shape = Shape(i % 4);
    p.a = {-900 + 75.0 * i, -600 + 47.0 * (i % 7), 3000 + 37.0 * i};
    p.b = p.a + Vec3(200, 300 - 25.0 * i, 50);
    p.ra = 80 + i, p.rb = 40 + 2 * i;
    p.axes << 120, 30, 0, 0, 200, 10, 20, 0, 90;
    p.material.pattern = Pattern(i % 4);
    p.material.period_mm = 35;
    p.material.albedo2 = 0.1f;
    p.human = i % 2;
    prims.push_back(p);
  }
  const int saved = omp_get_max_threads();
  RenderedFrame one, two;
  omp_set_num_threads(1);
  render(cam, prims, l, 0.003, one);
  omp_set_num_threads(2);
  render(cam, prims, l, 0.003, two);
  omp_set_num_threads(saved);
  CHECK(mask_count(one) > 2000);
  CHECK(one.intensity == two.intensity);
  CHECK(one.mask == two.mask);
  CHECK(one.depth_mm == two.depth_mm);
  RenderedFrame explicit2;
  render(cam, prims, l, 0.003, explicit2, RenderOptions{8, 2});
  CHECK(explicit2.intensity == one.intensity);
}

TEST_CASE("render.bad camera and degenerate primitives") {
  CameraModel cam = identity_camera();
  RenderedFrame f;
  cam.fx = 0;
  CHECK_THROWS_AS(render(cam, {}, flat_light(), 0, f), std::invalid_argument);
  cam = identity_camera();
  cam.width = 0;
  CHECK_THROWS_AS(render(cam, {}, flat_light(), 0, f), std::invalid_argument);
  cam = identity_camera();
  CHECK_THROWS_AS(render(cam, {}, flat_light(), 0, f, RenderOptions{3, 0}), std::invalid_argument);
  // Degenerate or non-finite primitives are skipped, never crash; behind the camera: unseen.
  Primitive flat = quad({0, 0, 1000}, {100, 0, 0}, {200, 0, 0});
  Primitive nan = sphere({std::nan(""), 0, 1000}, 100);
  Primitive squashed = sphere({0, 0, 1000}, 100);
  squashed.axes.col(2).setZero();
  Primitive behind = sphere({0, 0, -3000}, 500);
  Primitive around = sphere({0, 0, 0}, 500);  // the camera is inside: sees the far side
  render(cam, {flat, nan, squashed, behind}, flat_light(), 0, f);
  CHECK(mask_count(f) == 0);
  render(cam, {around}, flat_light(), 0, f);
  CHECK(f.depth_mm[at(f, 173, 130)] == Approx(500).margin(1e-3));
  // Odd sizes work.
  cam.width = 37, cam.height = 19, cam.cx = 18, cam.cy = 9, cam.fx = cam.fy = 40;
  render(cam, {sphere({0, 0, 3000}, 500)}, flat_light(), 0, f);
  CHECK(f.intensity.size() == 37u * 19u);
  CHECK(f.mask[at(f, 18, 9)] == 1);
}
