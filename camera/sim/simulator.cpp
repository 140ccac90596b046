#include "camera/sim/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace {

// Independent random streams of one recording, all derived from its seed.
enum Stream : std::uint64_t { kSceneStream = 1, kDresserStream, kPixelStream, kDanceStream };

std::uint64_t sub_seed(std::uint64_t seed, Stream s) { return hash64(seed, 0x51u, s); }

std::unique_ptr<Motion> make_motion(const SimSpec& spec, const BodyShape& shape) {
  const std::string& m = spec.motion;
  if (m.rfind("dance", 0) == 0) {
    // "dance" draws its style from the recording's seed; "dance<N>" fixes it to N.
    std::uint64_t style = sub_seed(spec.seed, kDanceStream);
    if (m.size() > 5) {
      const std::string digits = m.substr(5);
      if (digits.find_first_not_of("0123456789") != std::string::npos)
        throw std::invalid_argument("motion '" + m + "': expected 'dance' or 'dance<number>'");
      style = std::stoull(digits);
    }
    DanceParams p = random_dance_params(style);
    p.static_legs = spec.dance_static_legs;
    return make_procedural_dance(p, shape, style, spec.duration_s + spec.motion_offset_s + 1.0);
  }
  const std::string dir = spec.mocap_dir.empty() ? default_mocap_dir() : spec.mocap_dir;
  const std::filesystem::path path = std::filesystem::path(dir) / (m + ".bvh");
  if (!std::filesystem::exists(path))
    throw std::invalid_argument("motion '" + m + "': no " + path.string() +
                                " (a BVH stem in the mocap folder, or 'dance' for a procedural dance)");
  return load_bvh_motion(path.string(), shape, spec.motion_options);
}

// A motion turned about the vertical and shifted on the floor (SimSpec::frame_dancer).
class FramedMotion final : public Motion {
 public:
  FramedMotion(std::unique_ptr<Motion> inner, const Eigen::Matrix3d& turn, const Vec3& shift)
      : inner_(std::move(inner)), turn_(turn), shift_(shift) {}
  double duration_s() const override { return inner_->duration_s(); }
  BodyPose at(double t_s) const override {
    BodyPose p = inner_->at(t_s);
    for (auto& v : p.p) v = turn_ * v - shift_;
    return p;
  }
  std::string name() const override { return inner_->name(); }

 private:
  std::unique_ptr<Motion> inner_;
  Eigen::Matrix3d turn_;
  Vec3 shift_;
};

Character varied_character(const SimSpec& spec) {
  if (!(spec.height_scale >= 0.7 && spec.height_scale <= 1.3) || !(spec.girth_scale >= 0.6 && spec.girth_scale <= 1.6))
    throw std::invalid_argument("height scale must be in [0.7, 1.3] and girth scale in [0.6, 1.6]");
  if (!(spec.front_print >= 0 && spec.front_print <= 3)) throw std::invalid_argument("front print must be in [0, 3]");
  Character c = character_by_name(spec.character);
  if (spec.looks_seed) c = random_looks(c, spec.looks_seed);
  c.shape.height_mm *= spec.height_scale;
  c.shape.girth *= spec.girth_scale;
  if (spec.clothing) c.clothing = *spec.clothing;
  c.front_print = spec.front_print;
  return c;
}

SceneConfig seeded_scene(const SimSpec& spec) {
  SceneConfig c = spec.scene;
  c.seed = sub_seed(spec.seed, kSceneStream);
  return c;
}

}  // namespace

std::string default_mocap_dir() {
  if (const char* env = std::getenv("YELAN_MOCAP_DIR")) return env;
#ifdef YELAN_SOURCE_DIR
  const std::filesystem::path beside = std::filesystem::path(YELAN_SOURCE_DIR) / ".." / "shared" / "data" / "mocap";
  if (std::filesystem::exists(beside)) return beside.lexically_normal().string();
#endif
  return "../shared/data/mocap";
}

Simulator::Simulator(const SimSpec& spec)
    : spec_(spec),
      character_(varied_character(spec)),
      motion_(make_motion(spec, character_.shape)),
      dresser_(character_, sub_seed(spec.seed, kDresserStream)),
      scene_(seeded_scene(spec)),
      pixel_(scene_.camera().width, scene_.camera().height, spec.pixel, sub_seed(spec.seed, kPixelStream)) {
  if (!(spec.motion_begin >= 0 && spec.motion_begin < spec.motion_end && spec.motion_end <= 1) ||
      !(spec.motion_offset_s >= 0 && spec.motion_offset_s < 1e6))
    throw std::invalid_argument("motion segment must satisfy 0 <= begin < end <= 1 and the offset be >= 0 s");
  for (double o : spec.arm_offset_s)
    if (!(o >= 0 && o <= 60)) throw std::invalid_argument("arm offsets must lie in 0..60 s, got " + std::to_string(o));
  if (spec.free_arms_seed != 0 && (spec.arm_offset_s[0] != 0 || spec.arm_offset_s[1] != 0))
    throw std::invalid_argument("free arms and remixed arms (arm_offset_s) exclude each other: give one");
  if (!(spec.duration_s > 0) || spec.duration_s > 24 * 3600)
    throw std::invalid_argument("duration must be in (0 s, 24 h], got " + std::to_string(spec.duration_s));
  if (!(spec.label_hz >= 1 && spec.label_hz <= 10000) || !(spec.mask_hz >= 1 && spec.mask_hz <= 1000))
    throw std::invalid_argument("label rate must be 1..10000 Hz and mask rate 1..1000 Hz");
  if (!(spec.min_step_s > 0 && spec.min_step_s <= spec.max_step_s && spec.max_step_s <= 0.1 &&
        spec.max_render_step_s > 0 && spec.max_render_step_s <= 0.1))
    throw std::invalid_argument("need 0 < min_step <= max_step <= 0.1 s and 0 < max_render_step <= 0.1 s");
  if (!(spec.step_lambda > 0) || !(spec.render_lambda > 0)) throw std::invalid_argument("step lambdas must be > 0");
  pixel_dt_ = spec.max_step_s;
  render_dt_ = std::max(spec.max_render_step_s, spec.max_step_s);
  if (spec.frame_dancer && spec.dancer) frame_motion();
  if (spec.free_arms_seed != 0) free_arms_ = std::make_unique<FreeArms>(character_.shape, spec.free_arms_seed, spec.duration_s);
}

void Simulator::frame_motion() {
  // Facing -y at the recording's start, as a clip's first frame is and as the views are defined.
  const Eigen::Matrix3d turn = turn_to_face_minus_y(motion_->at(motion_time(0)));
  Vec3 mean = Vec3::Zero();
  const int n = 25;
  for (int i = 0; i < n; ++i) mean += turn * motion_->at(motion_time(spec_.duration_s * (i + 0.5) / n)).p[kPelvis];
  mean /= n;
  motion_ = std::make_unique<FramedMotion>(std::move(motion_), turn, Vec3(mean.x(), mean.y(), 0));
}

Simulator::~Simulator() = default;

double Simulator::image_speed(const BodyPose& a, const BodyPose& b, double dt) const {
  if (!(dt > 0)) return 0;
  const CameraModel& cam = scene_.camera();
  double worst = 0;
  for (int i = 0; i < kBodyPointCount; ++i) {
    const Vec3 ca = cam.M.leftCols<3>() * a.p[i] + cam.M.col(3), cb = cam.M.leftCols<3>() * b.p[i] + cam.M.col(3);
    if (ca.z() < 100 || cb.z() < 100) continue;
    const double du = cam.fx * (ca.x() / ca.z() - cb.x() / cb.z()), dv = cam.fy * (ca.y() / ca.z() - cb.y() / cb.z());
    worst = std::max(worst, std::hypot(du, dv));
  }
  return worst / dt;
}

double Simulator::motion_time(double t_s) const {
  // Past its end a segment plays backwards, then forwards again: positions stay continuous.
  const double full = motion_->duration_s();
  if (!(full > 0)) return t_s;
  const double a = spec_.motion_begin * full, d = (spec_.motion_end - spec_.motion_begin) * full;
  const double u = t_s + spec_.motion_offset_s;
  if (!(d > 0)) return a;
  if (u <= d) return a + u;
  const double m = std::fmod(u, 2 * d);
  return a + (m <= d ? m : 2 * d - m);
}

BodyPose Simulator::pose_at(double t_s) const {
  const BodyPose body = motion_->at(motion_time(t_s));
  BodyPose p = body;
  // Each arm into the unremixed body's chest frame: the other arm's shoulder must not tilt it.
  for (int side = 0; side < 2; ++side)
    if (spec_.arm_offset_s[side] != 0) {
      const BodyPose m = with_arm_from(body, motion_->at(motion_time(t_s + spec_.arm_offset_s[side])), side);
      for (int point : kRightArmPoints) p.p[point + side] = m.p[point + side];
    }
  return free_arms_ ? free_arms_->apply(p, t_s) : p;
}

void Simulator::sample(double t_s) {
  prev_pose_ = pose_;
  pose_ = pose_at(t_s);
  const BodyPose& pose = pose_;
  dresser_.update(pose, t_s);
  prims_.clear();
  if (spec_.dancer) dresser_.primitives(prims_);
  const auto t0 = std::chrono::steady_clock::now();
  scene_.render(t_s, prims_, frame_, /*flicker=*/false);
  stats_.render_wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ++stats_.samples;
}

Label Simulator::label_at(double t_s) const {
  const Joints13 world = dhp19_joints(pose_at(t_s));
  const CameraModel cam = scene_.camera_at(t_s);
  Label l;
  l.t_us = std::llround(t_s * 1e6);
  for (int j = 0; j < kJointCount; ++j) {
    const Vec3 c = cam.M.leftCols<3>() * world[j] + cam.M.col(3);
    l.joints_mm[j] = c;
    bool ok = c.z() > 1.0;
    if (ok) {
      const double u = cam.fx * c.x() / c.z() + cam.cx, v = cam.fy * c.y() / c.z() + cam.cy;
      ok = u >= 0 && u < cam.width && v >= 0 && v < cam.height;
    }
    l.valid[j] = ok && spec_.dancer;
  }
  return l;
}

const float* Simulator::lit(const float* intensity, double t_s) {
  const Lighting& light = scene_.light();
  if (light.flicker_depth == 0) return intensity;
  const float gain = float(light.flicker(t_s));
  lit_.resize(frame_.intensity.size());
  for (std::size_t k = 0; k < lit_.size(); ++k) lit_[k] = intensity[k] * gain;
  return lit_.data();
}

void Simulator::run_until(double t_end_s, SimSink& sink) {
  t_end_s = std::min(t_end_s, spec_.duration_s);
  const double label_dt = 1.0 / spec_.label_hz, mask_dt = 1.0 / spec_.mask_hz;
  const double lambda = spec_.step_lambda * std::min(spec_.pixel.pos_threshold, spec_.pixel.neg_threshold);
  if (!started_) {
    sample(0.0);
    pixel_.reset(lit(frame_.intensity.data(), 0.0), 0.0);
    sink.mask(0, frame_);
    next_mask_ = 1;
    ++stats_.masks;
    started_ = true;
  }
  auto emit_labels = [&](double upto) {
    for (double tl; (tl = next_label_ * label_dt) <= upto + 1e-12; ++next_label_) {
      sink.label(label_at(tl));
      ++stats_.labels;
    }
  };
  emit_labels(t_);
  while (t_ < t_end_s - 1e-12) {
    // The next rendered keyframe; it lands exactly on mask ticks, so each mask is rendered.
    const double t_mask = next_mask_ * mask_dt;
    double t1 = std::min({t_ + render_dt_, t_end_s, t_mask});
    if (t_mask - t1 < spec_.min_step_s * 0.5 && t_mask <= t_end_s) t1 = t_mask;
    prev_intensity_.assign(frame_.intensity.begin(), frame_.intensity.end());
    sample(t1);
    // Pixel steps between the keyframes over linearly interpolated intensity (as v2e does
    // between frames); event times are interpolated within each step by the pixel model.
    const int n = std::max(1, int(std::ceil((t1 - t_) / pixel_dt_ - 1e-9)));
    const auto p0 = std::chrono::steady_clock::now();
    double ts0 = t_;
    for (int i = 1; i <= n; ++i) {
      const double ts = i == n ? t1 : t_ + (t1 - t_) * i / n;
      const float* in = frame_.intensity.data();
      if (i < n) {
        const float w = float(i) / float(n);
        interp_.resize(prev_intensity_.size());
        for (std::size_t k = 0; k < interp_.size(); ++k)
          interp_[k] = prev_intensity_[k] + w * (frame_.intensity[k] - prev_intensity_[k]);
        in = interp_.data();
      }
      in = lit(in, ts);
      events_.clear();
      pixel_.step(in, ts0, ts, events_);
      ++stats_.pixel_steps;
      stats_.events += events_.size();
      if (!events_.empty()) sink.events(events_);
      ts0 = ts;
    }
    stats_.pixel_wall_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - p0).count();
    emit_labels(t1);
    if (std::abs(t1 - t_mask) < 1e-12) {
      sink.mask(std::llround(t_mask * 1e6), frame_);
      ++next_mask_;
      ++stats_.masks;
    }
    const double step = t1 - t_;
    step_sum_ += step;
    stats_.min_step_s = stats_.min_step_s == 0 ? step : std::min(stats_.min_step_s, step);
    // Next steps from the fastest body point's image speed over this one: a pixel step moves
    // edges at most step_lambda px (a pixel's log intensity by that fraction of the edge's
    // contrast), a keyframe at most render_lambda px; flicker bounds the pixel steps to
    // step_lambda thresholds of log change. Keyframes are rendered without flicker and each
    // pixel step applies its own instant's factor (`lit`), so flicker, a gain on the whole
    // frame, needs no keyframes of its own (it forced them to the pixel rate: 4.5x the cost
    // of a dancer under 30% flicker, measured 2026-11-28).
    // Capped at 3000 px/s (a hand at 15 m/s, 2.5 m away): motion capture glitches (a toe
    // flipping within one frame, in 05_16 and 05_19) must not drive sampling to its floor.
    const double speed = std::min(std::max(image_speed(prev_pose_, pose_, step), scene_.camera_image_speed()), 3000.0);
    double want_pixel = speed > 1e-6 ? spec_.step_lambda / speed : spec_.max_step_s;
    const double want_render = speed > 1e-6 ? spec_.render_lambda / speed : spec_.max_render_step_s;
    if (const Lighting& l = scene_.light(); l.flicker_depth > 0) {  // the lamp `lit` applies
      const double rate = 2 * 3.141592653589793 * l.flicker_hz * l.flicker_depth;  // peak d(log I)/dt
      want_pixel = std::min(want_pixel, lambda / rate);
    }
    pixel_dt_ = std::clamp(want_pixel, spec_.min_step_s, spec_.max_step_s);
    render_dt_ = std::clamp(want_render, pixel_dt_, std::max(spec_.max_render_step_s, spec_.max_step_s));
    t_ = t1;
  }
  stats_.mean_step_s = stats_.samples > 1 ? step_sum_ / double(stats_.samples - 1) : 0;
  stats_.pixel = pixel_.stats();
}

std::string Simulator::description_json() const {
  const SceneConfig& sc = scene_.config();
  nlohmann::ordered_json j = {
      {"name", spec_.name},
      {"character", character_.name},
      {"clothing", clothing_name(character_.clothing)},
      {"looks_seed", spec_.looks_seed},
      {"frame_dancer", spec_.frame_dancer},
      {"height_mm", character_.shape.height_mm},
      {"test_only_character", character_.test_only},
      {"dancer", spec_.dancer},
      {"motion", spec_.motion},
      {"speed", spec_.motion_options.speed},
      {"mirror", spec_.motion_options.mirror},
      {"motion_segment", {spec_.motion_begin, spec_.motion_end}},
      {"motion_offset_s", spec_.motion_offset_s},
      {"girth", character_.shape.girth},
      {"view", view_name(sc.view)},
      {"yaw_deg", sc.yaw_deg ? *sc.yaw_deg : view_yaw_deg(sc.view)},
      {"distance_mm", sc.distance_mm},
      {"lighting", light_name(sc.light)},
      {"flicker", sc.flicker},
      {"camera_motion", camera_motion_name(sc.camera_motion)},
      {"background", sc.background == SceneConfig::dynamic ? "dynamic" : "static"},
      {"occluders", sc.occluders},
      {"seed", spec_.seed},
      {"duration_s", spec_.duration_s},
      {"label_hz", spec_.label_hz},
      {"mask_hz", spec_.mask_hz},
      {"scene", scene_.description()}};
  // Only where it overrides the lighting's level, so the descriptions of other scenes keep their bytes.
  if (sc.light_dn && *sc.light_dn != lighting(sc.light, false).level) j["light_dn"] = *sc.light_dn;
  if (sc.clutter) j["clutter"] = true;
  if (spec_.arm_offset_s[0] != 0 || spec_.arm_offset_s[1] != 0) j["arm_offset_s"] = spec_.arm_offset_s;
  if (spec_.free_arms_seed != 0) j["free_arms_seed"] = spec_.free_arms_seed;
  if (spec_.front_print != 1) j["front_print"] = spec_.front_print;
  return j.dump();
}

}  // namespace yelan::camera::sim
