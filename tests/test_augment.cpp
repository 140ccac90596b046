// The geometric augmentation: a warped (or mirrored) picture and its warped (mirrored)
// joints or masks agree, the identity changes nothing, and the trainer's batch carries both.
#include <catch2/catch.hpp>

#include <cmath>

#include "camera/sim/presets.h"
#include "camera/sim/window_stream.h"
#include "engine/train/augment.h"
#include "engine/train/batch.h"
#include "layers/buffer.h"
#include "layers/simple.h"

using namespace yelan::train;

namespace {

// Centre of mass of channel c of frame 0, in sensor pixels, and its total.
std::array<double, 3> centroid(const yelan::layers::Act& a, int c, int d) {
  double sx = 0, sy = 0, m = 0;
  for (int y = 0; y < a.h; ++y)
    for (int x = 0; x < a.w; ++x) {
      const double v = a.data[(std::size_t(y) * a.w + x) * 16 + c];
      sx += v * (x + 0.5) * d, sy += v * (y + 0.5) * d, m += v;
    }
  return {sx / m, sy / m, m};
}

// One window of a preset with the frames the mask stage's labels read after its input.
yelan::camera::sim::SimWindow mask_stage_window(const yelan::ModelConfig& cfg, const std::string& preset) {
  namespace sim = yelan::camera::sim;
  sim::WindowStreamOptions o;
  o.window = cfg.window + cfg.n_masks - 1;
  o.warmup_s = 0.1;
  o.scene_s = o.warmup_s + o.window / o.frame_hz + 1e-6;
  sim::SimWindowStream stream({sim::preset_spec(preset)}, 5, o);
  sim::SimWindow w;
  stream.next(w);
  return w;
}

}  // namespace

TEST_CASE("augment: a warped frame moves a blob where warp_point moves its centre", "[train]") {
  const int d = 2, sw = 346, sh = 260;
  yelan::layers::ActBuf buf;
  buf.resize(1, 6, sh / d, sw / d);
  const yelan::layers::Act& a = buf.act;
  std::fill(a.data, a.data + a.floats(), 0.f);
  const double bx = 60.3, by = 40.7;  // cells
  for (int y = 0; y < a.h; ++y)
    for (int x = 0; x < a.w; ++x) {
      const double r2 = (x - bx) * (x - bx) + (y - by) * (y - by);
      a.data[(std::size_t(y) * a.w + x) * 16 + 0] = float(std::exp(-r2 / 18));
      a.data[(std::size_t(y) * a.w + x) * 16 + 5] = float(0.5 * std::exp(-r2 / 18));
    }
  const auto before = centroid(a, 0, d);
  const Similarity s{1.15, 0.2, 12, -7};
  warp_frame(a, 0, s, d, sw, sh);
  const auto want = warp_point(s, before[0], before[1], sw, sh);
  for (int c : {0, 5}) {
    const auto after = centroid(a, c, d);
    CHECK(after[0] == Approx(want[0]).margin(0.3));
    CHECK(after[1] == Approx(want[1]).margin(0.3));
  }
  CHECK(centroid(a, 0, d)[2] == Approx(before[2] * s.scale * s.scale).epsilon(0.03));  // the area grows
  // Rotating by a quarter turn about the centre takes a point right of it below it.
  const auto q = warp_point({1, 3.141592653589793 / 2, 0, 0}, 173 + 10, 130, sw, sh);
  CHECK(q[0] == Approx(173).margin(1e-9));
  CHECK(q[1] == Approx(140).margin(1e-9));
  // Shifted out of the frame, nothing is left.
  warp_frame(a, 0, {1, 0, double(sw), 0}, d, sw, sh);
  CHECK(centroid(a, 0, d)[2] == 0);
}

TEST_CASE("augment: a warped joint projects where the warp moves its image point, its depth offset kept", "[train]") {
  const Intrinsics k{485, 480, 171, 128, 346, 260};
  const std::array<double, 3> p{-300, 200, 3800};
  const double zr = 3500;
  const Similarity s{0.85, -0.15, -20, 9};
  const auto q = warp_joint(s, p, k, zr);
  const auto uv = warp_point(s, k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy, k.width, k.height);
  CHECK(k.fx * q[0] / q[2] + k.cx == Approx(uv[0]).margin(1e-9));
  CHECK(k.fy * q[1] / q[2] + k.cy == Approx(uv[1]).margin(1e-9));
  CHECK(q[2] - zr / s.scale == Approx(p[2] - zr).margin(1e-9));
  CHECK(warp_joint(s, {0, 0, zr}, k, zr)[2] == Approx(zr / s.scale));
  const auto same = warp_joint(Similarity{}, p, k, zr);
  for (int i = 0; i < 3; ++i) CHECK(same[i] == Approx(p[i]).margin(1e-9));
}

TEST_CASE("augment: the batch under the identity warp is the plain batch, and under a warp its targets are the warped joints", "[train]") {
  namespace sim = yelan::camera::sim;
  const yelan::ModelConfig cfg = yelan::load_model_config(std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/small-nomask.json");
  sim::WindowStreamOptions o;
  o.window = cfg.window;
  o.warmup_s = 0.04;
  o.scene_s = 0.04 + o.window / o.frame_hz + 1e-6;
  sim::SimWindowStream stream({sim::preset_spec("ben-dance7-front-high-static")}, 5, o);
  sim::SimWindow w;
  stream.next(w);
  yelan::MaskNet unused(cfg);
  BatchBuilder plain(cfg, 1, MaskSource::truth), same(cfg, 1, MaskSource::truth), warped(cfg, 1, MaskSource::truth);
  plain.add(w, unused, nullptr);
  const Similarity id{}, s{1.2, 0.25, 15, -10};
  same.add(w, unused, nullptr, &id);
  warped.add(w, unused, nullptr, &s);
  const Batch &a = plain.batch(), &b = same.batch(), &c = warped.batch();
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.input.act.floats(); ++i) differ += std::abs(a.input.act.data[i] - b.input.act.data[i]) > 1e-6f;
  CHECK(differ == 0);
  for (std::size_t i = 0; i < a.target.size(); ++i) REQUIRE(a.target[i] == Approx(b.target[i]).margin(1e-9));
  int checked = 0;
  for (int f = 0; f < cfg.window; ++f) {
    const auto& fr = w.frames[std::size_t(f)];
    const double zr = fr.joints_mm[0].z();
    CHECK(c.z_ref[std::size_t(f)] == Approx(zr / s.scale));
    for (int j = 0; j < kJoints; ++j) {
      if (!c.valid_u8[std::size_t(f) * kJoints + j]) continue;
      const auto q = warp_joint(s, {fr.joints_mm[j].x(), fr.joints_mm[j].y(), fr.joints_mm[j].z()}, c.k, zr);
      const auto n = normalise_joint(q, c.k, zr / s.scale);
      for (int i = 0; i < 3; ++i) REQUIRE(c.target[(std::size_t(f) * kJoints + j) * 3 + i] == Approx(n[i]).margin(1e-6));
      ++checked;
    }
  }
  CHECK(checked > cfg.window * 8);
}

TEST_CASE("augment: the mask stage's labels move with its warped input and stay binary", "[train]") {
  namespace sim = yelan::camera::sim;
  yelan::ModelConfig cfg = yelan::load_model_config(std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/small-nomask.json");
  cfg.window = 1;  // as --mask-frames 1 trains: one input frame, n_masks label frames
  const sim::SimWindow w = mask_stage_window(cfg, "ben-dance7-front-high-static");
  yelan::MaskNet unused(cfg);
  BatchBuilder plain(cfg, 1, MaskSource::none), same(cfg, 1, MaskSource::none), warped(cfg, 1, MaskSource::none);
  const Similarity id{}, s{0.85, 0.2, 40, -10};  // shrunk: the whole dancer stays in the frame
  plain.add(w, unused, nullptr);
  same.add(w, unused, nullptr, &id);
  warped.add(w, unused, nullptr, &s);
  const auto &a = plain.batch().labels.act, &b = same.batch().labels.act, &c = warped.batch().labels.act;
  for (std::size_t i = 0; i < a.floats(); ++i) REQUIRE(a.data[i] == b.data[i]);
  for (std::size_t i = 0; i < c.floats(); ++i) REQUIRE((c.data[i] == 0.f || c.data[i] == 1.f));
  const int d = cfg.downscale;
  for (int k : {0, cfg.n_masks - 1}) {  // the current mask and the farthest future one
    const auto before = centroid(a, k, d), after = centroid(c, k, d);
    REQUIRE(before[2] > 1000);  // the dancer covers thousands of cells
    const auto want = warp_point(s, before[0], before[1], cfg.sensor_width, cfg.sensor_height);
    CHECK(after[0] == Approx(want[0]).margin(1.5));
    CHECK(after[1] == Approx(want[1]).margin(1.5));
    CHECK(after[2] == Approx(before[2] * s.scale * s.scale).epsilon(0.1));
  }
  // The input moved with its labels: the share of the events' mass on the current mask holds.
  auto on_mask = [&](const Batch& bt) {
    const auto& in = bt.input.act;
    const auto& lab = bt.labels.act;
    double on = 0, all = 0;
    for (std::size_t i = 0; i < in.pixels(); ++i) {
      const double v = in.data[i * 16];  // channel 0 of frame 0
      all += v;
      on += v * lab.data[i * 16];
    }
    return on / all;
  };
  const double share = on_mask(plain.batch()), share_w = on_mask(warped.batch());
  REQUIRE(share > 0.15);  // the rest: the background's events
  CHECK(share_w == Approx(share).margin(0.03));
  // Had the labels stayed put, part of the dancer's events would fall off them.
  BatchBuilder input_only(cfg, 1, MaskSource::none);
  input_only.add(w, unused, nullptr);
  warp_frame(input_only.batch().input.act, 0, s, d, cfg.sensor_width, cfg.sensor_height);
  CHECK(on_mask(input_only.batch()) < share - 0.05);
}

TEST_CASE("augment: a mirrored frame trades cell x with w - 1 - x in every channel, and twice is the frame", "[train]") {
  yelan::layers::ActBuf buf;
  buf.resize(2, 20, 3, 7);  // two channel blocks, an odd width (the middle column stays)
  const yelan::layers::Act& a = buf.act;
  auto at = [&](int n, int c, int y, int x) -> float& {
    return a.data[((std::size_t(n) * a.cb() + c / 16) * a.pixels() + std::size_t(y) * a.w + x) * 16 + c % 16];
  };
  for (int n = 0; n < 2; ++n)
    for (int c = 0; c < 20; ++c)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 7; ++x) at(n, c, y, x) = float(n * 10000 + c * 100 + y * 10 + x);
  yelan::layers::flip_frame(a, 1);
  for (int c = 0; c < 20; ++c)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 7; ++x) {
        REQUIRE(at(1, c, y, x) == float(10000 + c * 100 + y * 10 + (6 - x)));
        REQUIRE(at(0, c, y, x) == float(c * 100 + y * 10 + x));  // the other frame untouched
      }
  yelan::layers::flip_frame(a, 1);
  for (int c = 0; c < 20; ++c) CHECK(at(1, c, 2, 1) == float(10000 + c * 100 + 21));
}

TEST_CASE("augment: a mirrored joint projects to the mirrored image point, its v and depth kept", "[train]") {
  const Intrinsics k{485, 480, 171, 128, 346, 260};
  const std::array<double, 3> p{-300, 200, 3800};
  const auto q = flip_joint(p, k, 173, 2);
  const double u = k.fx * p[0] / p[2] + k.cx;
  CHECK(k.fx * q[0] / q[2] + k.cx == Approx(346 - u).margin(1e-9));
  CHECK(q[1] == p[1]);
  CHECK(q[2] == p[2]);
  const auto back = flip_joint(q, k, 173, 2);
  for (int i = 0; i < 3; ++i) CHECK(back[i] == Approx(p[i]).margin(1e-9));
}

TEST_CASE("augment: a mirrored batch is the plain one mirrored, labels and joints with it, left and right swapped", "[train]") {
  namespace sim = yelan::camera::sim;
  yelan::ModelConfig cfg = yelan::load_model_config(std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/small-nomask.json");
  cfg.window = 1;
  const sim::SimWindow w = mask_stage_window(cfg, "ben-dance7-right-high-static");
  yelan::MaskNet unused(cfg);
  const Similarity s{0.9, 0.1, 20, -5};
  for (const MaskSource src : {MaskSource::none, MaskSource::truth}) {
    for (const bool warped : {false, true}) {
      INFO("mask stage " << (src == MaskSource::none) << ", warped " << warped);
      BatchBuilder plain(cfg, 1, src), mirrored(cfg, 1, src);
      plain.add(w, unused, nullptr, warped ? &s : nullptr);
      mirrored.add(w, unused, nullptr, warped ? &s : nullptr, true);
      const Batch &a = plain.batch(), &b = mirrored.batch();
      // The input and (mask stage) every label plane: exactly the plain batch's, mirrored.
      std::vector<const yelan::layers::Act*> planes = {&a.input.act};
      if (src == MaskSource::none) planes.push_back(&a.labels.act);
      for (std::size_t i = 0; i < planes.size(); ++i) {
        const auto& pa = *planes[i];
        const auto& pb = i == 0 ? b.input.act : b.labels.act;
        double mass = 0;
        for (int cb = 0; cb < pa.cb(); ++cb)
          for (int y = 0; y < pa.h; ++y)
            for (int x = 0; x < pa.w; ++x)
              for (int l = 0; l < 16; ++l) {
                const std::size_t ia = ((std::size_t(cb) * pa.pixels()) + std::size_t(y) * pa.w + x) * 16 + l;
                const std::size_t ib = ((std::size_t(cb) * pa.pixels()) + std::size_t(y) * pa.w + (pa.w - 1 - x)) * 16 + l;
                REQUIRE(pb.data[ib] == pa.data[ia]);
                mass += pa.data[ia];
              }
        CHECK(mass > 100);  // something there to mirror
      }
      // The joints: the partner's, mirrored through the camera; their validity swaps too.
      const int pairs[13] = {0, 2, 1, 4, 3, 6, 5, 8, 7, 10, 9, 12, 11};
      int valid = 0;
      for (int j = 0; j < kJoints; ++j) {
        const int pj = pairs[j];
        REQUIRE(b.valid_u8[std::size_t(j)] == a.valid_u8[std::size_t(pj)]);
        const auto want = flip_joint(a.truth_mm[0][std::size_t(pj)], a.k, cfg.width(), cfg.downscale);
        for (int c = 0; c < 3; ++c) CHECK(b.truth_mm[0][std::size_t(j)][std::size_t(c)] == Approx(want[std::size_t(c)]).margin(1e-6));
        if (!b.valid_u8[std::size_t(j)]) continue;
        ++valid;
        const auto n = normalise_joint(want, b.k, b.z_ref[0]);
        for (int c = 0; c < 3; ++c) CHECK(b.target[std::size_t(j) * 3 + std::size_t(c)] == Approx(n[std::size_t(c)]).margin(1e-6));
      }
      CHECK(valid >= 10);
      CHECK(b.z_ref[0] == a.z_ref[0]);
    }
  }
}

TEST_CASE("augment: the framing similarity centres the window's joint box and fills the frame with it", "[train]") {
  namespace sim = yelan::camera::sim;
  sim::SimWindow w;  // the default camera: fx = fy = 485, centre (173, 130), 346 x 260
  w.frames.resize(4);
  const double z = 4850;  // u = x / 10 + 173, v = y / 10 + 130
  auto put = [&](int f, int j, double u, double v, bool valid) {
    w.frames[std::size_t(f)].joints_mm[std::size_t(j)] = {(u - 173) * 10, (v - 130) * 10, z};
    w.frames[std::size_t(f)].valid[std::size_t(j)] = valid;
  };
  put(1, 0, 100, 80, true);
  put(2, 5, 140, 160, true);
  put(2, 6, 300, 10, false);  // not valid: ignored
  put(0, 3, 340, 250, true);  // before the frames asked about: ignored
  put(3, 3, 5, 5, true);      // after them: ignored
  const Similarity s = framing_similarity(w, 1, 2, 0.1, 4);
  // box 40 x 80 px, grown to 48 x 96: the height binds, 260 / 96
  CHECK(s.scale == Approx(260.0 / 96));
  CHECK(s.angle_rad == 0);
  const auto lo = warp_point(s, 100, 80, 346, 260), hi = warp_point(s, 140, 160, 346, 260);
  CHECK((lo[0] + hi[0]) / 2 == Approx(173));
  CHECK((lo[1] + hi[1]) / 2 == Approx(130));
  CHECK(hi[1] - lo[1] == Approx(260 / 1.2));
  // a tiny dancer is zoomed at most `most`; one bigger than the frame only centred
  put(1, 0, 150, 120, true);
  put(2, 5, 152, 124, true);
  CHECK(framing_similarity(w, 1, 2, 0.1, 4).scale == 4);
  put(1, 0, -50, 20, true);
  put(2, 5, 300, 290, true);
  const Similarity big = framing_similarity(w, 1, 2, 0.1, 4);
  CHECK(big.scale == 1);
  CHECK(warp_point(big, 125, 155, 346, 260)[0] == Approx(173));
  CHECK(warp_point(big, 125, 155, 346, 260)[1] == Approx(130));
  // nobody: the identity
  for (auto& f : w.frames) f.valid.fill(0);
  const Similarity none = framing_similarity(w, 0, 4);
  CHECK((none.scale == 1 && none.shift_x == 0 && none.shift_y == 0));
}
