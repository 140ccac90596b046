#include "camera/sim/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include <Eigen/Geometry>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace {

constexpr double kDeg = 3.141592653589793 / 180.0;
constexpr double kTwoPi = 6.283185307179586;

// Rng streams, one per part of the layout, so adding a part never shifts another's draws.
enum Stream : std::uint64_t {
  kWallStream = 0x5743'0001,
  kOccluderStream = 0x5743'0002,
  kMoverStream = 0x5743'0003,
  kCurtainStream = 0x5743'0004,
  kScreenStream = 0x5743'0005,
  kWalkerStream = 0x5743'0006,
  kCameraMotionStream = 0x5743'0007,
  kClutterStream = 0x5743'0008,
};

Primitive quad(const Vec3& corner, const Vec3& e0, const Vec3& e1, const Material& m) {
  Primitive p;
  p.shape = Shape::quad;
  p.a = corner;
  p.axes.col(0) = e0;
  p.axes.col(1) = e1;
  p.axes.col(2) = e0.cross(e1).normalized();
  p.material = m;
  return p;
}

Primitive capsule(const Vec3& a, const Vec3& b, double ra, double rb, const Material& m) {
  Primitive p;
  p.shape = Shape::round_cone;
  p.a = a, p.b = b, p.ra = ra, p.rb = rb;
  p.material = m;
  return p;
}

Material textured(Rng& rng, Pattern pattern, double period_lo, double period_hi, double lo,
                  double hi, const Vec3& origin, const Vec3& u, const Vec3& v) {
  Material m;
  m.pattern = pattern;
  m.albedo = float(rng.uniform(lo, hi));
  m.albedo2 = float(rng.uniform(lo, hi) * 0.45);
  m.period_mm = float(rng.uniform(period_lo, period_hi));
  m.origin = origin, m.u_axis = u, m.v_axis = v;
  m.print_seed = std::uint32_t(rng.bits());
  return m;
}

// An open-bottomed box (5 faces) standing on the floor: centre of its footprint c,
// width along `along`, depth along `across`.
void add_box(std::vector<Primitive>& out, const Vec3& c, const Vec3& along, const Vec3& across,
             double width, double depth, double height, const Material& m) {
  const Vec3 up = Vec3::UnitZ();
  const Vec3 ew = along * width, ed = across * depth, eh = up * height;
  const Vec3 c0 = c - 0.5 * ew - 0.5 * ed;
  Material mm = m;
  mm.origin = c0;
  mm.u_axis = along, mm.v_axis = up;
  out.push_back(quad(c0, ew, eh, mm));                // face towards -across
  out.push_back(quad(c0 + ed, ew, eh, mm));           // face towards +across
  mm.u_axis = across;
  out.push_back(quad(c0, ed, eh, mm));                // side
  out.push_back(quad(c0 + ew, ed, eh, mm));           // side
  mm.u_axis = along, mm.v_axis = across;
  out.push_back(quad(c0 + eh, ew, ed, mm));           // top
}

Pattern any_pattern(Rng& r) {
  const Pattern all[4] = {Pattern::plain, Pattern::stripes, Pattern::checks, Pattern::print};
  return all[r.below(4)];
}

// A furnished room: what a real room puts in front of an event camera (SceneConfig::clutter).
// `ahead`, `right`: horizontal unit vectors from the camera towards the dancer's spot and to
// the image's right; the wall stands wall_mm beyond the spot, the camera distance_mm before it.
void add_clutter(Rng& r, const Vec3& ahead, const Vec3& right, double wall_mm, double distance_mm,
                 std::vector<Primitive>& out) {
  const Vec3 up = Vec3::UnitZ();
  const int posters = 6 + r.below(7);
  for (int i = 0; i < posters; ++i) {
    const double w = r.uniform(200, 1600), h = r.uniform(200, 1600);
    const Vec3 c0 = (wall_mm - r.uniform(5, 300)) * ahead + r.uniform(-5000, 5000) * right + r.uniform(0, 2400) * up;
    out.push_back(quad(c0, w * right, h * up, textured(r, any_pattern(r), 20, 250, 0.05, 0.95, c0, right, up)));
  }
  // Floor items stand between 1.2 m before the camera and the wall, off the dancer's spot.
  auto floor_spot = [&](double clear_mm) {
    Vec3 c;
    do {
      c = r.uniform(-(distance_mm - 1200), wall_mm - 400) * ahead + r.uniform(-3500, 3500) * right;
    } while (std::fabs(c.dot(ahead)) < clear_mm && std::fabs(c.dot(right)) < clear_mm);
    return c;
  };
  const int boxes = 2 + r.below(5);
  for (int i = 0; i < boxes; ++i) {
    const double w = r.uniform(300, 1500), d = r.uniform(300, 800), h = r.uniform(300, 1900);
    const Vec3 c = floor_spot(700 + 0.5 * std::max(w, d));
    add_box(out, c, right, ahead, w, d, h, textured(r, any_pattern(r), 30, 300, 0.05, 0.9, c, right, up));
  }
  const int poles = 1 + r.below(4);  // a person-tall vertical edge is what stage 1 mistakes for a dancer
  for (int i = 0; i < poles; ++i) {
    const Vec3 c = floor_spot(700);
    const double rad = r.uniform(15, 90);
    out.push_back(capsule(c, c + r.uniform(1200, 2800) * up, rad, rad,
                          textured(r, any_pattern(r), 30, 200, 0.05, 0.9, c, up, right)));
  }
  const int lamps = 1 + r.below(3);
  for (int i = 0; i < lamps; ++i) {
    Primitive lamp;
    lamp.shape = Shape::ellipsoid;
    lamp.a = floor_spot(700) + r.uniform(1800, 2700) * up;
    const double rad = r.uniform(60, 200);
    lamp.axes = Eigen::Vector3d(rad, rad, rad * r.uniform(0.5, 1.2)).asDiagonal();
    lamp.material.albedo = lamp.material.albedo2 = float(r.uniform(0.85, 1.0));
    out.push_back(lamp);
  }
}

// Position along the wall of something moving at speed from phase, wrapping over span.
double wrapped(double t_s, double speed, double phase, double span) {
  double s = std::fmod(phase + speed * t_s, span);
  if (s < 0) s += span;
  return s - 0.5 * span;
}

}  // namespace

double view_yaw_deg(View v) {
  switch (v) {
    case View::front: return 0;
    case View::left: return 90;
    case View::back: return 180;
    case View::right: return -90;
  }
  return 0;
}

const char* view_name(View v) {
  switch (v) {
    case View::front: return "front";
    case View::back: return "back";
    case View::left: return "left";
    case View::right: return "right";
  }
  return "?";
}

const char* light_name(LightLevel l) {
  switch (l) {
    case LightLevel::high: return "high";
    case LightLevel::medium: return "medium";
    case LightLevel::low: return "low";
  }
  return "?";
}

const char* camera_motion_name(int motion) {
  switch (motion) {
    case SceneConfig::still: return "still";
    case SceneConfig::pan: return "pan";
    case SceneConfig::shake: return "shake";
    case SceneConfig::sweep: return "sweep";
  }
  return "?";
}

CameraModel davis346(double focal_px) {
  CameraModel c;
  c.width = 346, c.height = 260;
  c.fx = c.fy = focal_px;
  c.cx = 173, c.cy = 130;
  return c;
}

CameraModel orbit_camera(double yaw_deg, double pitch_deg, double distance_mm, double height_mm,
                         const CameraModel& intrinsics) {
  if (!(distance_mm > 0) || !std::isfinite(distance_mm) || !std::isfinite(height_mm) ||
      !std::isfinite(yaw_deg))
    throw std::invalid_argument("camera: distance " + std::to_string(distance_mm) +
                                " mm, height " + std::to_string(height_mm) + " mm, yaw " +
                                std::to_string(yaw_deg) + " deg: need finite, distance > 0");
  if (std::isnan(pitch_deg)) pitch_deg = std::atan2(height_mm - kBodyAimHeightMm, distance_mm) / kDeg;
  if (!(std::fabs(pitch_deg) < 89))
    throw std::invalid_argument("camera: pitch " + std::to_string(pitch_deg) +
                                " deg is outside (-89, 89)");
  const double yaw = yaw_deg * kDeg, pitch = pitch_deg * kDeg;
  const Vec3 ahead(-std::sin(yaw), std::cos(yaw), 0);
  const Vec3 centre = -distance_mm * ahead + Vec3(0, 0, height_mm);
  const Vec3 forward = std::cos(pitch) * ahead - std::sin(pitch) * Vec3::UnitZ();
  const Vec3 right = ahead.cross(Vec3::UnitZ());
  const Vec3 down = forward.cross(right);
  CameraModel cam = intrinsics;
  Eigen::Matrix3d R;
  R.row(0) = right.transpose();
  R.row(1) = down.transpose();
  R.row(2) = forward.transpose();
  cam.M.leftCols<3>() = R;
  cam.M.col(3) = -R * centre;
  return cam;
}

CameraModel view_camera(View v, double distance_mm, double height_mm, double pitch_deg,
                        double focal_px) {
  return orbit_camera(view_yaw_deg(v), pitch_deg, distance_mm, height_mm, davis346(focal_px));
}

Vec3 camera_centre(const CameraModel& cam) {
  const Eigen::Matrix3d R = cam.M.leftCols<3>();
  return -R.transpose() * cam.M.col(3);
}

Lighting lighting(LightLevel level, bool flicker) {
  Lighting l;
  l.key_dir = Vec3(0.35, -0.55, 0.76).normalized();  // a lamp above, front-left of the dancer
  switch (level) {
    case LightLevel::high: l.level = 255, l.ambient = 0.45, l.flicker_depth = 0.10; break;
    case LightLevel::medium: l.level = 60, l.ambient = 0.35, l.flicker_depth = 0.20; break;
    // Low puts white facing the lamp at the pixel's lin-log knee (20 DN). At 4 DN (until
    // 2026-11-27) a dancer's pixels fired 1.2 events/s against the noise's 1.13 elsewhere:
    // no dancer in the events at all, where the paper's low light has fewer events and more
    // noise but a dancer (at 20 DN: 3.5 against 1.2; medium 60 DN: 9.5).
    case LightLevel::low: l.level = 20, l.ambient = 0.25, l.flicker_depth = 0.30; break;
  }
  if (!flicker) l.flicker_depth = 0;
  l.flicker_hz = 100;
  return l;
}

void set_low_light_dn(SceneConfig& scene, std::optional<double> dn) {
  if (dn && scene.light == LightLevel::low) scene.light_dn = dn;
}

Scene::Scene(const SceneConfig& config)
    : config_(config), light_(lighting(config.light, config.flicker)), renderer_(config.render), moving_(config.render) {
  if (config.light_dn) {
    if (!(*config.light_dn > 0 && *config.light_dn <= 1e5))
      throw std::invalid_argument("scene: light_dn " + std::to_string(*config.light_dn) + " must be in (0, 1e5]");
    light_.level = *config.light_dn;
  }
  const double yaw = config.yaw_deg ? *config.yaw_deg : view_yaw_deg(config.view);
  const CameraModel cam =
      orbit_camera(yaw, config.pitch_deg, config.distance_mm, config.height_mm, config.intrinsics);
  ahead_ = Vec3(-std::sin(yaw * kDeg), std::cos(yaw * kDeg), 0);
  right_ = ahead_.cross(Vec3::UnitZ());
  const Vec3 up = Vec3::UnitZ();
  const std::uint64_t seed = config.seed;

  // Wall 2-3 m behind the dancer, floor from behind the camera to the wall.
  Rng wr(seed, kWallStream);
  wall_mm_ = wr.uniform(2000, 3000);
  const double half = 15000, height = 8000, behind = config.distance_mm + 2000;
  const Vec3 wall0 = wall_mm_ * ahead_ - half * right_;
  const Pattern wall_pattern = wr.uniform() < 0.5 ? Pattern::print : Pattern::stripes;
  static_.push_back(quad(wall0, 2 * half * right_, height * up,
                         textured(wr, wall_pattern, 120, 300, 0.35, 0.7, wall0, right_, up)));
  const Vec3 floor0 = -behind * ahead_ - half * right_;
  static_.push_back(quad(floor0, 2 * half * right_, (behind + wall_mm_) * ahead_,
                         textured(wr, Pattern::checks, 300, 600, 0.25, 0.5, floor0, right_, ahead_)));

  if (config.clutter) {
    Rng crng(seed, kClutterStream);
    add_clutter(crng, ahead_, right_, wall_mm_, config.distance_mm, static_);
  }

  if (config.occluders) {
    Rng orng(seed, kOccluderStream);
    const double side = orng.uniform() < 0.5 ? -1 : 1;
    // A box low enough to hide a leg, and a pillar on the other side; both partly cover the
    // dancer from this camera.
    const Vec3 box_c = -orng.uniform(700, 1200) * ahead_ + side * orng.uniform(250, 500) * right_;
    add_box(static_, box_c, right_, ahead_, orng.uniform(450, 700), orng.uniform(350, 500),
            orng.uniform(450, 800),
            textured(orng, Pattern::print, 80, 160, 0.4, 0.7, box_c, right_, up));
    const Vec3 pil = -orng.uniform(500, 1000) * ahead_ - side * orng.uniform(300, 550) * right_;
    const double pr = orng.uniform(120, 180);
    static_.push_back(capsule(pil - pr * up, pil + 2800 * up, pr, pr,
                              textured(orng, Pattern::stripes, 100, 200, 0.3, 0.6, pil, up, right_)));
    // A cardboard panel crossing between camera and dancer.
    const double pw = orng.uniform(500, 800), ph = orng.uniform(1200, 1900);
    const double depth = std::min(1500.0, 0.45 * config.distance_mm);
    Material pm = textured(orng, Pattern::print, 60, 140, 0.4, 0.7, Vec3::Zero(), right_, up);
    panel_ = quad(-depth * ahead_ + orng.uniform(0, 300) * up, pw * right_, ph * up, pm);
    // Wraps just outside the field of view, so it crosses every few seconds.
    const double half_view =
        (config.distance_mm - depth) * (config.intrinsics.width / 2.0) / config.intrinsics.fx;
    panel_speed_ = side * orng.uniform(800, 1400);
    panel_span_ = 2 * (half_view + pw) + 1000;
    panel_phase_ = orng.uniform(0, panel_span_);
  }

  if (config.background == SceneConfig::dynamic) {
    // Boxes/"cars" sliding along the wall.
    Rng mr(seed, kMoverStream);
    for (int i = 0; i < 2; ++i) {
      Mover m;
      const double w = mr.uniform(600, 1400), d = mr.uniform(400, 700), h = mr.uniform(400, 900);
      add_box(m.parts, (wall_mm_ - 150 - d / 2 - 700 * i) * ahead_, right_, ahead_, w, d, h,
              textured(mr, i ? Pattern::stripes : Pattern::print, 80, 200, 0.3, 0.9,
                       Vec3::Zero(), right_, up));
      m.speed_mm_s = (mr.uniform() < 0.5 ? -1 : 1) * mr.uniform(400, 2000);
      m.span_mm = 16000;
      m.phase_mm = mr.uniform(0, m.span_mm);
      movers_.push_back(std::move(m));
    }
    // A person walking along the wall (not the dancer: not in the mask).
    Rng pr(seed, kWalkerStream);
    Mover walker;
    walker.walker = true;
    walker.parts.push_back(capsule(Vec3::Zero(), Vec3::Zero(), 0, 0,
                                   textured(pr, Pattern::stripes, 40, 90, 0.3, 0.8, Vec3::Zero(), up, right_)));
    walker.parts.push_back(capsule(Vec3::Zero(), Vec3::Zero(), 0, 0,
                                   textured(pr, Pattern::plain, 40, 90, 0.1, 0.4, Vec3::Zero(), up, right_)));
    walker.speed_mm_s = (pr.uniform() < 0.5 ? -1 : 1) * pr.uniform(1000, 1500);
    walker.span_mm = 16000;
    walker.phase_mm = pr.uniform(0, walker.span_mm);
    movers_.push_back(std::move(walker));
    // A curtain of strips hanging near the wall on one side, waving.
    Rng cr(seed, kCurtainStream);
    const double cx = (cr.uniform() < 0.5 ? -1 : 1) * cr.uniform(1200, 2200);
    Material cm = textured(cr, Pattern::stripes, 50, 120, 0.4, 0.8, Vec3::Zero(), right_, up);
    for (int i = 0; i < 6; ++i) {
      const Vec3 top = (wall_mm_ - 250) * ahead_ + (cx + 220 * i) * right_ + 2700 * up;
      Material m = cm;
      m.origin = top;
      curtain_.push_back(quad(top, 220 * right_, -2500 * up, m));
      curtain_phase_.push_back(cr.uniform(0, kTwoPi));
    }
    // A screen on the wall whose picture changes 30 times a second.
    Rng sr(seed, kScreenStream);
    const Vec3 sc = (wall_mm_ - 20) * ahead_ + sr.uniform(-1500, 1500) * right_ + 1300 * up;
    Material sm = textured(sr, Pattern::checks, 60, 160, 0.7, 0.95, sc, right_, up);
    sm.albedo2 = 0.08f;
    screen_ = quad(sc, 1100 * right_, 650 * up, sm);
  }
  renderer_.set_static(cam, static_, light_);
  Rng mr(seed, kCameraMotionStream);
  if (config.camera_motion == SceneConfig::pan) {
    wobble_[1][0] = {6 * kDeg, kTwoPi / 8, mr.uniform(0, kTwoPi)};
  } else if (config.camera_motion == SceneConfig::shake) {
    for (auto& axis : wobble_) {
      axis[0] = {0.3 * kDeg, kTwoPi * mr.uniform(2, 4), mr.uniform(0, kTwoPi)};
      axis[1] = {0.2 * kDeg, kTwoPi * mr.uniform(5, 7), mr.uniform(0, kTwoPi)};
    }
  } else if (config.camera_motion == SceneConfig::sweep) {
    const double amp_lo[3] = {1, 2, 0.3}, amp_hi[3] = {4, 8, 1.2};  // tilt, pan, roll (deg)
    for (std::size_t a = 0; a < 3; ++a) {
      wobble_[a][0] = {mr.uniform(amp_lo[a], amp_hi[a]) * kDeg, kTwoPi * mr.uniform(0.1, 0.5), mr.uniform(0, kTwoPi)};
      wobble_[a][1] = {0.25 * mr.uniform(amp_lo[a], amp_hi[a]) * kDeg, kTwoPi * mr.uniform(0.6, 1.4), mr.uniform(0, kTwoPi)};
    }
  }
}

CameraModel Scene::camera_at(double t_s) const {
  CameraModel cam = camera();
  if (config_.camera_motion == SceneConfig::still) return cam;
  double angle[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a)
    for (const Wobble& w : wobble_[std::size_t(a)]) angle[a] += w.amp * std::sin(w.rate * t_s + w.phase);
  // A rotation about the camera's centre: applied in the camera frame, after the world one.
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(angle[2], Vec3::UnitZ()) * Eigen::AngleAxisd(angle[1], Vec3::UnitY()) *
                             Eigen::AngleAxisd(angle[0], Vec3::UnitX()))
                                .toRotationMatrix();
  cam.M = r * cam.M;
  return cam;
}

double Scene::camera_image_speed() const {
  const CameraModel& cam = camera();
  const double half_diagonal = 0.5 * std::hypot(cam.width, cam.height);
  double rate = 0;  // rad/s, every axis's worst case summed
  for (const auto& axis : wobble_)
    for (const Wobble& w : axis) rate += w.amp * w.rate;
  return (std::max(cam.fx, cam.fy) + half_diagonal) * rate;
}

void Scene::dynamic_primitives(double t_s, std::vector<Primitive>& out) const {
  const Vec3 up = Vec3::UnitZ();
  for (const Mover& m : movers_) {
    const double s = wrapped(t_s, m.speed_mm_s, m.phase_mm, m.span_mm);
    if (!m.walker) {
      for (Primitive p : m.parts) {
        p.a += s * right_;
        p.material.origin += s * right_;
        out.push_back(p);
      }
      continue;
    }
    // Walker: stride phase from distance walked (1.4 m per gait cycle).
    const Vec3 base = (wall_mm_ - 700) * ahead_ + s * right_;
    const double phase = kTwoPi * (m.phase_mm + m.speed_mm_s * t_s) / 1400.0;
    const double dir = m.speed_mm_s > 0 ? 1 : -1;
    const Material& shirt = m.parts[0].material;
    const Material& legs = m.parts[1].material;
    auto mat = [&](const Material& src) {
      Material r = src;
      r.origin = base;
      return r;
    };
    const Vec3 hip = base + 950 * up, neck = base + 1450 * up;
    out.push_back(capsule(hip, neck, 150, 170, mat(shirt)));
    Primitive head;
    head.shape = Shape::ellipsoid;
    head.a = neck + 170 * up;
    head.axes = Eigen::Vector3d(90, 90, 115).asDiagonal();
    head.material = mat(legs);
    out.push_back(head);
    for (int side = -1; side <= 1; side += 2) {
      const double swing = 0.4 * side * std::sin(phase);
      const Vec3 fwd = dir * right_;
      const Vec3 h = hip + side * 90 * ahead_;
      const Vec3 foot = h + 900 * (std::sin(swing) * fwd - std::cos(swing) * up);
      out.push_back(capsule(h, foot, 70, 50, mat(legs)));
      const Vec3 sh = neck - 50 * up + side * 190 * ahead_;
      const Vec3 hand = sh + 650 * (-std::sin(swing) * fwd - std::cos(swing) * up);
      out.push_back(capsule(sh, hand, 50, 40, mat(shirt)));
    }
  }
  for (std::size_t i = 0; i < curtain_.size(); ++i) {
    Primitive p = curtain_[i];
    const double sway = 120 * std::sin(kTwoPi * 0.6 * t_s + curtain_phase_[i]);
    p.axes.col(1) += sway * ahead_;
    out.push_back(p);
  }
  if (screen_) {
    Primitive p = *screen_;
    const auto frame = std::uint64_t(std::floor(t_s * 30));
    const double shift = uniform01(config_.seed, kScreenStream ^ 0xf00d, frame);
    p.material.origin += shift * p.material.period_mm * 2 * (right_ + up);
    out.push_back(p);
  }
  if (panel_) {
    Primitive p = *panel_;
    const double s = wrapped(t_s, panel_speed_, panel_phase_, panel_span_);
    p.a += s * right_;
    p.material.origin = p.a;
    out.push_back(p);
  }
}

void Scene::render(double t_s, const std::vector<Primitive>& human, RenderedFrame& out, bool flicker) {
  frame_prims_.clear();
  frame_prims_.insert(frame_prims_.end(), human.begin(), human.end());
  dynamic_primitives(t_s, frame_prims_);
  Renderer* r = &renderer_;
  if (config_.camera_motion != SceneConfig::still) {
    // A moving camera sees the static layer move too: the whole frame, from scratch.
    frame_prims_.insert(frame_prims_.end(), static_.begin(), static_.end());
    moving_.set_static(camera_at(t_s), {}, light_);
    r = &moving_;
  }
  if (flicker)
    r->render(t_s, frame_prims_, out);
  else
    r->render_unflickered(frame_prims_, out);
}

std::string Scene::description() const {
  const CameraModel& cam = camera();
  const Vec3 c = camera_centre(cam);
  const double yaw = config_.yaw_deg ? *config_.yaw_deg : view_yaw_deg(config_.view);
  const double pitch = std::isnan(config_.pitch_deg)
                           ? std::atan2(config_.height_mm - kBodyAimHeightMm, config_.distance_mm) / kDeg
                           : config_.pitch_deg;
  char buf[640];
  std::snprintf(buf, sizeof buf,
                "camera: %s yaw %.1f deg, pitch %.1f deg (down), distance %.0f mm, centre "
                "(%.0f, %.0f, %.0f) mm, %dx%d f=%.1f px; light %s (level %.0f, ambient %.2f), "
                "flicker %s; wall %.0f mm behind the dancer; background %s; occluders %s; "
                "seed %llu",
                config_.yaw_deg ? "orbit" : view_name(config_.view), yaw, pitch,
                config_.distance_mm, c.x(), c.y(), c.z(), cam.width, cam.height, cam.fx,
                light_name(config_.light), light_.level, light_.ambient,
                light_.flicker_depth > 0
                    ? (std::to_string(int(std::lround(light_.flicker_depth * 100))) + "% at 100 Hz").c_str()
                    : "off",
                wall_mm_,
                config_.background == SceneConfig::dynamic
                    ? "dynamic (2 sliding boxes, a walker, a waving curtain, a screen)"
                    : "static wall",
                config_.occluders ? "box, pillar, crossing panel" : "none",
                static_cast<unsigned long long>(config_.seed));
  // Only for scenes that have them, so the descriptions of earlier scenes keep their bytes.
  std::string d = buf;
  if (config_.clutter) d += "; a furnished room";
  if (config_.camera_motion == SceneConfig::sweep) d += "; camera sweeping (hand-held)";
  return d;
}

}  // namespace yelan::camera::sim
