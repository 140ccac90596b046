// The simulator as a whole: sampling, labels, masks, events, determinism, recordings.
#include <catch2/catch.hpp>
#include <hdf5.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "camera/io/event_reader.h"
#include "camera/io/h5.h"
#include "camera/sim/presets.h"
#include "camera/sim/simulator.h"
#include "test_util.h"

using namespace yelan::camera;
using namespace yelan::camera::sim;

namespace {

struct Collect final : SimSink {
  std::vector<Event> ev;
  std::vector<Label> labels;
  std::vector<std::int64_t> mask_t;
  std::vector<std::size_t> mask_area;
  void events(std::span<const Event> e) override { ev.insert(ev.end(), e.begin(), e.end()); }
  void label(const Label& l) override { labels.push_back(l); }
  void mask(std::int64_t t, const RenderedFrame& f) override {
    mask_t.push_back(t);
    std::size_t n = 0;
    for (auto m : f.mask) n += m != 0;
    mask_area.push_back(n);
  }
};

SimSpec dance_spec(double duration = 0.1) {
  SimSpec s = preset_spec("ben-dance7-front-high-static");
  s.duration_s = duration;
  s.seed = 11;
  return s;
}

bool same_events(const std::vector<Event>& a, const std::vector<Event>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].t != b[i].t || a[i].x != b[i].x || a[i].y != b[i].y || a[i].p != b[i].p) return false;
  return true;
}

}  // namespace

TEST_CASE("sim: labels at 300 Hz, masks at 50 Hz, sorted events inside the sensor", "[sim]") {
  Simulator sim(dance_spec(0.1));
  Collect c;
  sim.run_until(1.0, c);  // stops at the duration
  CHECK(sim.time_s() == Approx(0.1));
  REQUIRE(c.labels.size() == 31);  // t = 0, 1/300, ..., 0.1
  CHECK(c.labels[3].t_us == 10000);
  REQUIRE(c.mask_t.size() == 6);  // 0, 20, ..., 100 ms
  CHECK(c.mask_t[5] == 100000);
  REQUIRE(!c.ev.empty());
  for (std::size_t i = 1; i < c.ev.size(); ++i) REQUIRE(c.ev[i - 1].t <= c.ev[i].t);
  for (const Event& e : c.ev) {
    REQUIRE(e.x < 346);
    REQUIRE(e.y < 260);
    REQUIRE(e.t > 0);
    REQUIRE(e.t <= 100000);
  }
  // The dancer fills part of the image; every mask shows her.
  for (auto a : c.mask_area) {
    CHECK(a > 1000);
    CHECK(a < 346 * 260 / 2);
  }
}

TEST_CASE("sim: joint labels are the camera-frame projection of the body, valid inside the image", "[sim]") {
  Simulator sim(dance_spec(0.05));
  const CameraModel& cam = sim.camera();
  const Label l = sim.label_at(0.02);
  CHECK(l.t_us == 20000);
  for (int j = 0; j < kJointCount; ++j) {
    const Vec3& c = l.joints_mm[j];
    // A front camera 3.5 m away: every joint in front of it, about that far.
    CHECK(c.z() > 2000);
    CHECK(c.z() < 5000);
    const double u = cam.fx * c.x() / c.z() + cam.cx, v = cam.fy * c.y() / c.z() + cam.cy;
    CHECK(l.valid[j] == (u >= 0 && u < 346 && v >= 0 && v < 260));
  }
  // Head above the feet in the image (y down).
  CHECK(l.joints_mm[0].y() / l.joints_mm[0].z() < l.joints_mm[11].y() / l.joints_mm[11].z());
}

TEST_CASE("sim: the same seed gives the same events, whatever the thread count", "[sim]") {
  auto run = [](int threads, std::uint64_t seed) {
    omp_set_num_threads(threads);
    SimSpec s = dance_spec(0.06);
    s.seed = seed;
    Simulator sim(s);
    Collect c;
    sim.run_until(1.0, c);
    return c;
  };
  const Collect a = run(1, 5), b = run(2, 5), d = run(2, 6);
  omp_set_num_threads(omp_get_num_procs());
  CHECK(same_events(a.ev, b.ev));
  CHECK_FALSE(same_events(a.ev, d.ev));
  REQUIRE(a.labels.size() == b.labels.size());
  for (std::size_t i = 0; i < a.labels.size(); ++i)
    for (int j = 0; j < kJointCount; ++j) REQUIRE(a.labels[i].joints_mm[j] == b.labels[i].joints_mm[j]);
}

TEST_CASE("sim: a static scene with noise off and a still dancer makes no events", "[sim]") {
  SimSpec s = preset_spec("ben-dance7-front-high-static");
  s.dance_static_legs = true;
  s.pixel = pixel_params_clean();
  s.duration_s = 0.02;
  // No motion at all: a BVH would move; a dance at zero speed does not exist, so compare the
  // clean pixel against the noisy one on the same scene instead: noise adds events.
  Simulator clean(s);
  Collect a;
  clean.run_until(1, a);
  s.pixel = pixel_params_noisy();
  Simulator noisy(s);
  Collect b;
  noisy.run_until(1, b);
  CHECK(b.ev.size() > a.ev.size());
}

TEST_CASE("sim: flicker adds pixel steps, not keyframes, and its events follow the lamp", "[sim]") {
  // An empty room under a low lamp (30% flicker), the clean pixel: nothing moves, so every
  // event is the lamp's. Keyframes are rendered without flicker and each pixel step applies
  // its instant's factor: the flickering scene renders as many keyframes as the steady one
  // (it rendered one per pixel step when keyframes carried the flicker).
  SimSpec s = preset_spec("front-low-static-empty");
  s.pixel = pixel_params_clean();
  s.duration_s = 0.1;
  s.seed = 3;
  Simulator steady(s);
  Collect a;
  steady.run_until(1, a);
  s.scene.flicker = true;
  Simulator lit(s);
  Collect b;
  lit.run_until(1, b);
  CHECK(lit.stats().samples == steady.stats().samples);
  CHECK(lit.stats().pixel_steps > steady.stats().pixel_steps);
  CHECK(a.ev.size() < 100);
  REQUIRE(b.ev.size() > 10000);
  // The factor 1 + m cos(2 pi 100 t) rises where sin(2 pi 100 t) < 0: ON events there.
  std::size_t agree = 0;
  for (const Event& e : b.ev) {
    const double rising = -std::sin(2 * 3.141592653589793 * 100 * e.t * 1e-6);
    agree += (rising > 0) == (e.p == 1);
  }
  CHECK(double(agree) / double(b.ev.size()) > 0.95);
  // Both polarities, about as many of each (the lamp returns where it was every 10 ms).
  std::size_t on = 0;
  for (const Event& e : b.ev) on += e.p;
  CHECK(double(on) / double(b.ev.size()) == Approx(0.5).margin(0.1));
}

TEST_CASE("sim: presets and scene.json", "[sim]") {
  const SimSpec a = preset_spec("front-low-dynamic");
  CHECK(a.scene.view == View::front);
  CHECK(a.scene.light == LightLevel::low);
  CHECK(a.scene.background == SceneConfig::dynamic);
  const SimSpec b = preset_spec("kurt-93_03-left-medium-static-occluded-flicker");
  CHECK(b.character == "kurt");
  CHECK(b.motion == "93_03");
  CHECK(b.scene.view == View::left);
  CHECK(b.scene.occluders);
  CHECK(b.scene.flicker);
  CHECK_THROWS_WITH(preset_spec("front-dim-static"), Catch::Contains("unknown lighting 'dim'"));
  CHECK_THROWS_WITH(preset_spec("zed-05_04-front-high-static"), Catch::Contains("zed"));
  CHECK_THROWS_WITH(preset_spec("front-high"), Catch::Contains("wrong number of fields"));
  const SimSpec j = spec_from_json(R"({"preset": "front-high-static", "character": "mia", "distance_mm": 5000,
                                       "pixel": {"pos_threshold": 0.3}, "seed": 9})", "scene.json");
  CHECK(j.character == "mia");
  CHECK(j.scene.distance_mm == 5000);
  CHECK(j.pixel.pos_threshold == 0.3);
  CHECK(j.seed == 9);
  CHECK_THROWS_WITH(spec_from_json(R"({"colour": 1})", "s.json"), Catch::Contains("s.json: unknown key 'colour'"));
  CHECK_THROWS_WITH(spec_from_json(R"({"view": "top"})", "s.json"), Catch::Contains("view 'top'"));
  CHECK_THROWS_WITH(spec_from_json("{", "s.json"), Catch::Contains("s.json: not JSON"));
  // The grid: 11 training characters x 14 motions x 4 x 3 x 2; 3 held-out x 6 motions x 24.
  CHECK(grid_presets("train").size() == 11 * 14 * 24);
  CHECK(grid_presets("test").size() == 3 * 6 * 24 * 2);  // clear and occluded
  const auto f = grid_presets("test", {{"jade"}, {"05_16"}, {"front"}, {}, {"static"}});
  REQUIRE(f.size() == 6);
  CHECK(f[0] == "jade-05_16-front-high-static");
  CHECK(f[1] == "jade-05_16-front-high-static-occluded");
  for (const auto& n : grid_presets("all")) REQUIRE_NOTHROW(preset_spec(n));
}

TEST_CASE("sim: a recording file holds events, camera, labels, masks and the scene", "[sim]") {
  const std::string path = "/tmp/yelan-sim-test-" + std::to_string(::getpid()) + ".yelan.h5";
  const SimStats st = write_recording(dance_spec(0.05), path);
  REQUIRE(std::filesystem::exists(path));
  auto reader = open_event_file(path);
  CHECK(reader->info().width == 346);
  std::vector<Event> all;
  while (reader->read(all, 4096) > 0) {
  }
  CHECK(all.size() == st.events);
  h5::H5Id f = h5::open_file(path);
  CHECK(h5::read_attr_string(f.get(), "format") == "yelan-recording");
  CHECK(h5::read_attr_string(f.get(), "character") == "ben");
  CHECK(h5::read_attr_string(f.get(), "scene")->find("\"lighting\":\"high\"") != std::string::npos);
  auto dims = [&](const char* name) {
    h5::H5Id ds = h5::check(H5Dopen2(f.get(), name, H5P_DEFAULT), name);
    return h5::shape(ds.get());
  };
  CHECK(dims("labels/joints") == std::vector<hsize_t>{16, 13, 3});
  CHECK(dims("labels/valid") == std::vector<hsize_t>{16, 13});
  CHECK(dims("labels/t") == std::vector<hsize_t>{16});
  CHECK(dims("masks/data") == std::vector<hsize_t>{3, 260, 346});
  CHECK(dims("camera/K") == std::vector<hsize_t>{3, 3});
  CHECK(dims("camera/M") == std::vector<hsize_t>{3, 4});
  std::filesystem::remove(path);
}

TEST_CASE("sim: CMU clips play from the mocap folder", "[sim]") {
  const std::string clip = yelan::test::shared_data_or_skip("mocap/05_16.bvh");
  SimSpec s = preset_spec("jade-05_16-back-medium-dynamic");
  s.mocap_dir = std::filesystem::path(clip).parent_path().string();
  s.duration_s = 0.04;
  Simulator sim(s);
  Collect c;
  sim.run_until(1, c);
  CHECK(c.labels.size() == 13);
  CHECK(c.mask_t.size() == 3);
  s.motion = "99_99";
  CHECK_THROWS_WITH(Simulator(s), Catch::Contains("99_99.bvh"));
}

#include "camera/sim/rng.h"
#include "camera/sim/window_stream.h"

TEST_CASE("sim: the window stream gives TORE, masks and joints per frame, reproducibly", "[sim]") {
  WindowStreamOptions o;
  o.window = 3;
  o.frame_hz = 50;
  o.warmup_s = 0.04;
  o.scene_s = 0.1;  // room for one window per scene: 40, 60, 80 ms
  std::vector<SimSpec> scenes = {preset_spec("ben-dance7-front-high-static"), preset_spec("lena-dance2-left-low-dynamic")};
  SimWindowStream a(scenes, 3, o), b(scenes, 3, o);
  SimWindow w, v;
  a.next(w);
  REQUIRE(w.frames.size() == 3);
  CHECK(w.frames[0].t_us == 40000);
  CHECK(w.frames[2].t_us == 80000);
  CHECK(w.scene == "ben-dance7-front-high-static");
  const SimFrame& f = w.frames[1];
  REQUIRE(f.tore.size() == 6u * 346 * 260);
  REQUIRE(f.mask.size() == 346u * 260);
  // TORE values in [0, 1]; the newest events (age < ~100 us) read 1; some pixels have events.
  std::size_t lit = 0;
  for (float x : f.tore) {
    REQUIRE(x >= 0.f);
    REQUIRE(x <= 1.f);
    lit += x > 0;
  }
  CHECK(lit > 100);
  // Events happen where the dancer moves: most lit pixels of pos0/neg0 lie near the mask.
  std::size_t mask_px = 0;
  for (auto m : f.mask) mask_px += m;
  CHECK(mask_px > 1000);
  CHECK(f.joints_mm[0].z() > 2000);
  a.next(w);  // the second scene
  CHECK(w.scene == "lena-dance2-left-low-dynamic");
  CHECK(a.scenes_started() == 2);
  b.next(v);
  b.next(v);
  CHECK(v.seed == w.seed);
  CHECK(v.frames[2].tore == w.frames[2].tore);
  CHECK(v.frames[2].mask == w.frames[2].mask);
}

TEST_CASE("sim: a recording longer than its clip plays the clip back and forth, continuously", "[sim]") {
  const std::string clip = yelan::test::shared_data_or_skip("mocap/02_03.bvh");  // 1.44 s after the T-pose
  SimSpec s = preset_spec("ben-02_03-front-high-static");
  s.mocap_dir = std::filesystem::path(clip).parent_path().string();
  s.duration_s = 4;
  Simulator sim(s);
  const double d = sim.motion_duration_s();
  CHECK(d == Approx(172 / 120.0));  // 173 frames after the T-pose, 120 Hz
  const Label a = sim.label_at(d - 0.2), b = sim.label_at(d + 0.2), c = sim.label_at(2 * d + 0.3), e = sim.label_at(0.3);
  for (int j = 0; j < kJointCount; ++j) {
    CHECK((a.joints_mm[j] - b.joints_mm[j]).norm() < 1e-6);  // mirrored in time about the end
    CHECK((c.joints_mm[j] - e.joints_mm[j]).norm() < 1e-6);  // and forwards again
  }
  double worst = 0;
  for (double t = d - 0.01; t < d + 0.01; t += 0.001) {
    const Label p = sim.label_at(t), q = sim.label_at(t + 0.001);
    for (int j = 0; j < kJointCount; ++j) worst = std::max(worst, (p.joints_mm[j] - q.joints_mm[j]).norm());
  }
  CHECK(worst < 20);  // mm per ms: no jump at the turn
}

TEST_CASE("sim: the window stream's event counts are the events of each frame period", "[sim]") {
  WindowStreamOptions o;
  o.window = 3;
  o.frame_hz = 50;
  o.warmup_s = 0.04;
  o.scene_s = 0.1;
  o.counts = true;
  const SimSpec scene = preset_spec("ben-dance7-front-high-static");
  SimWindowStream stream({scene}, 3, o);
  SimWindow w;
  stream.next(w);
  // The same scene run by hand, counting between the frame times (20, 40, 60, 80 ms).
  SimSpec spec = scene;
  spec.seed = hash64(3, 0x5717, 0) & 0xffffffffffffull;
  spec.duration_s = o.scene_s;
  spec.mask_hz = o.frame_hz;
  struct Counter : SimSink {
    std::vector<float> c = std::vector<float>(2u * 346 * 260, 0.f);
    void events(std::span<const Event> ev) override {
      for (const Event& e : ev) c[(e.p ? 0 : 346u * 260) + e.y * 346u + e.x] += 1.f;
    }
  } counter;
  Simulator sim(spec);
  sim.run_until(0.02, counter);
  double total = 0;
  for (int k = 0; k < 3; ++k) {
    std::fill(counter.c.begin(), counter.c.end(), 0.f);
    sim.run_until(0.04 + 0.02 * k, counter);
    INFO("frame " << k);
    REQUIRE(w.frames[std::size_t(k)].counts.size() == counter.c.size());
    CHECK(w.frames[std::size_t(k)].counts == counter.c);
    for (float v : counter.c) total += v;
  }
  CHECK(total > 1000);  // a dancer in bright light makes events
  o.counts = false;
  SimWindowStream plain({scene}, 3, o);
  plain.next(w);
  CHECK(w.frames[0].counts.empty());  // counting is opt-in
}

TEST_CASE("sim: a dancer shows in the events at every lighting, well above the noise", "[sim]") {
  // Events per pixel and second on the dancer's mask against the rest of the frame. At the
  // low light of datasets drawn before 2026-11-27 (4 DN) the two were 1.2 and 1.13: no dancer.
  struct InMask final : SimSink {
    std::vector<std::vector<std::uint8_t>> masks;
    std::vector<Event> ev;
    void events(std::span<const Event> e) override { ev.insert(ev.end(), e.begin(), e.end()); }
    void mask(std::int64_t, const RenderedFrame& f) override { masks.push_back(f.mask); }
  };
  for (const char* light : {"high", "medium", "low"}) {
    SimSpec s = preset_spec(std::string("ben-dance7-front-") + light + "-static");
    s.duration_s = 0.5;
    s.seed = 3;
    Simulator sim(s);
    InMask c;
    sim.run_until(1.0, c);
    REQUIRE(c.masks.size() == 26);  // every 20 ms from 0
    double in = 0, out = 0, in_px = 0;
    for (const Event& e : c.ev) {
      if (e.t < 200000) continue;  // the pixels settle
      const auto& m = c.masks[std::size_t((e.t + 10000) / 20000)];
      (m[std::size_t(e.y) * 346 + e.x] ? in : out) += 1;
    }
    for (std::size_t k = 10; k < c.masks.size(); ++k)
      for (auto v : c.masks[k]) in_px += v != 0;
    in_px /= double(c.masks.size() - 10);
    const double rate_in = in / in_px / 0.3, rate_out = out / (346.0 * 260 - in_px) / 0.3;  // per second
    INFO(light << ": mask " << in_px << " px, events per pixel and second on the dancer " << rate_in << ", elsewhere "
               << rate_out);
    CHECK(in_px > 2000);
    CHECK(rate_in > 2.5 * rate_out);
    CHECK(rate_out > 0.5);  // the noise is there (about 1 per second in the dark)
  }
}
