// The dataset's members: a pure function of (seed, split, index); the splits share no body
// and no stretch of a training clip; augmentation is drawn per recording and varies.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <span>
#include <sstream>

#include "camera/sim/characters.h"
#include "camera/sim/dataset.h"
#include "camera/sim/presets.h"
#include "camera/sim/simulator.h"
#include "test_util.h"

using namespace yelan::camera::sim;

TEST_CASE("dataset: members are seeded, splits hold out bodies and clip segments, augmentation varies", "[sim]") {
  const SimSpec a = dataset_member("train", 17, 3, 5.0), b = dataset_member("train", 17, 3, 5.0);
  CHECK(a.name == b.name);
  CHECK(a.seed == b.seed);
  CHECK(a.motion_offset_s == b.motion_offset_s);
  CHECK(dataset_member("train", 17, 4, 5.0).seed != a.seed);
  CHECK(dataset_file_name(a) == a.name + ".yelan.h5");
  std::set<std::string> chars[3], views, motions;
  int mirrored = 0, n = 0;
  double speed_lo = 9, speed_hi = 0;
  const char* splits[3] = {"train", "val", "test"};
  for (int s = 0; s < 3; ++s)
    for (int i = 0; i < 200; ++i) {
      const SimSpec m = dataset_member(splits[s], i, 1, 5.0);
      chars[s].insert(m.character);
      CHECK(m.name.rfind(std::string(splits[s]) + "-", 0) == 0);
      const bool dance = m.motion.rfind("dance", 0) == 0;
      const auto& clips = s == 2 ? test_motions() : train_motions();
      if (!dance) CHECK(std::find(clips.begin(), clips.end(), m.motion) != clips.end());
      // Training clips: the first 85% train, the rest validates.
      if (!dance && s == 0) CHECK(m.motion_end <= 0.85);
      if (!dance && s == 1) CHECK(m.motion_begin >= 0.85);
      if (s == 2) CHECK(character_by_name(m.character).test_only);
      views.insert(view_name(m.scene.view));
      motions.insert(m.motion);
      mirrored += m.motion_options.mirror;
      speed_lo = std::min(speed_lo, m.motion_options.speed), speed_hi = std::max(speed_hi, m.motion_options.speed);
      REQUIRE(m.scene.yaw_deg);
      CHECK(std::abs(*m.scene.yaw_deg - view_yaw_deg(m.scene.view)) <= 25);
      ++n;
    }
  for (const auto& c : chars[1]) CHECK(chars[0].count(c) == 0);  // validation bodies never train
  for (const auto& c : chars[2]) CHECK(chars[0].count(c) == 0);
  CHECK(chars[0].size() == dataset_characters("train").size());
  CHECK(views.size() == 4);
  CHECK(motions.size() > 10);
  CHECK(mirrored > n / 3);
  CHECK(mirrored < 2 * n / 3);
  CHECK(speed_lo < 0.8);
  CHECK(speed_hi > 1.3);
  CHECK_THROWS(dataset_member("holdout", 0, 1, 5.0));
}

TEST_CASE("dataset: a clip segment and a start offset play inside the segment, back and forth", "[sim]") {
  SimSpec s = preset_spec("ben-05_04-front-high-static");
  s.duration_s = 1;
  const Simulator whole(s);
  const double len = whole.motion_duration_s();
  s.motion_begin = 0.5, s.motion_end = 0.6, s.motion_offset_s = 0.02 * len;
  const Simulator seg(s);
  // At t = 0 the segment's pose is the whole clip's at 0.52 of its length.
  const Label a = seg.label_at(0), b = whole.label_at(0.52 * len);
  CHECK((a.joints_mm[7] - b.joints_mm[7]).norm() < 1e-6);
  // Past the segment's end it plays backwards: 0.12 len later it is at 0.56.
  const Label c = seg.label_at(0.12 * len), e = whole.label_at(0.56 * len);
  CHECK((c.joints_mm[7] - e.joints_mm[7]).norm() < 1e-6);
  s.motion_begin = 0.7, s.motion_end = 0.6;
  CHECK_THROWS(Simulator(s));
}

TEST_CASE("dataset: made in parallel, resumable (done files kept, a killed run's temp files removed), with a manifest, added to only at its low light", "[sim]") {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("yelan-dataset-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  DatasetSpec d;
  d.out_dir = dir.string();
  d.seed = 2;
  d.train = 2, d.val = 1, d.test = 1;
  d.duration_s = 0.5;
  d.threads = 2;
  std::ostringstream log;
  CHECK(make_dataset(d, log) == 4);
  const std::string first = dataset_file_name(dataset_member("train", 0, 2, 0.5));
  const auto path = dir / "train" / first;
  REQUIRE(std::filesystem::exists(path));
  CHECK(std::filesystem::exists(dir / "val" / dataset_file_name(dataset_member("val", 0, 2, 0.5))));
  CHECK(std::filesystem::exists(dir / "test" / dataset_file_name(dataset_member("test", 0, 2, 0.5))));
  const auto size = std::filesystem::file_size(path);
  // A killed run's leftovers (pid 999999999 is no process) go; done files stay.
  std::ofstream(dir / "train" / (first + ".tmp-999999999-abcdef")) << "partial";
  std::filesystem::remove(dir / "val" / dataset_file_name(dataset_member("val", 0, 2, 0.5)));
  CHECK(make_dataset(d, log) == 1);
  CHECK_FALSE(std::filesystem::exists(dir / "train" / (first + ".tmp-999999999-abcdef")));
  CHECK(std::filesystem::file_size(path) == size);
  std::ifstream m(dir / "manifest.json");
  std::stringstream text;
  text << m.rdbuf();
  CHECK(text.str().find("\"yelan-dataset-manifest\"") != std::string::npos);
  CHECK(text.str().find(first) != std::string::npos);
  CHECK(text.str().find("\"low_light_dn\": 20") != std::string::npos);
  CHECK((text.str().find("\"remix_arms\": 0,") != std::string::npos || text.str().find("\"remix_arms\": 0.0,") != std::string::npos));
  // Nor is a share of remixed arms other than the manifest's added to it.
  d.remix_arms = 0.5;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("--remix-arms 0"));
  d.remix_arms = 0;
  // Nor a share of free arms.
  CHECK((text.str().find("\"free_arms\": 0,") != std::string::npos || text.str().find("\"free_arms\": 0.0,") != std::string::npos));
  d.free_arms = 0.25;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("--free-arms 0"));
  d.free_arms = 0;
  // Nor at another scale of the front cues.
  CHECK((text.str().find("\"front_print\": 1,") != std::string::npos || text.str().find("\"front_print\": 1.0,") != std::string::npos));
  d.front_print = 2;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("--front-print 1"));
  d.front_print = 5;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("0..3"));
  d.front_print = 1;
  // Nor with scales drawn from a range where the manifest names one.
  d.front_print_max = 2;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("(its upper end) 1"));
  d.front_print_max = 1;
  // Low light is not in the names: adding at another level than the manifest's is refused.
  d.low_light_dn = 4;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("--low-light-dn 20"));
  // A manifest from before the key was drawn at 4 DN.
  std::string old = text.str();
  const auto key = old.find("\"low_light_dn\"");
  old.erase(key, old.find('\n', key) + 1 - key);
  std::ofstream(dir / "manifest.json") << old;
  CHECK(make_dataset(d, log) == 0);
  d.low_light_dn.reset();
  std::ofstream(dir / "manifest.json") << old;
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("--low-light-dn 4"));
  d.duration_s = 0;
  CHECK_THROWS_AS(make_dataset(d, log), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

TEST_CASE("dataset: a front-print range gives each dancer its own scale, the same on every run", "[sim]") {
  std::set<double> drawn;
  for (const char* split : {"train", "val", "test"})
    for (int i = 0; i < 40; ++i) {
      const SimSpec m = dataset_member(split, i, 2, 5.0);
      const double s = member_front_print(split, m, 2, 0.5, 2);
      CHECK(s >= 0.5);
      CHECK(s < 2);
      CHECK(s == member_front_print(split, m, 2, 0.5, 2));
      CHECK(member_front_print(split, m, 2, 1.5, 1.5) == 1.5);  // an empty range is its end
      drawn.insert(s);
    }
  CHECK(drawn.size() == 120);
  double below = 0;
  for (double s : drawn) below += s < 1.25;
  CHECK(below > 40);  // uniform over the range: about half under its middle
  CHECK(below < 80);
  CHECK(member_front_print("train", dataset_member("train", 3, 2, 5.0), 3, 0.5, 2) != member_front_print("train", dataset_member("train", 3, 2, 5.0), 2, 0.5, 2));
  CHECK(member_front_print("train", dataset_empty_member("train", 3, 2, 5.0), 2, 0.5, 2) == 0.5);  // nobody to dress
}

TEST_CASE("dataset: empty scenes have events from the room alone, no valid joint, empty masks", "[sim]") {
  struct Tally : SimSink {
    std::uint64_t n_events = 0, valid = 0, human = 0;
    void events(std::span<const yelan::camera::Event> ev) override { n_events += ev.size(); }
    void label(const Label& l) override {
      for (auto v : l.valid) valid += v;
    }
    void mask(std::int64_t, const RenderedFrame& f) override {
      for (auto m : f.mask) human += m != 0;
    }
  };
  SimSpec s = preset_spec("ben-05_04-front-medium-dynamic-flicker-empty");
  CHECK_FALSE(s.dancer);
  CHECK(s.scene.flicker);
  s.duration_s = 0.3;
  Simulator sim(s);
  Tally t;
  sim.run_until(s.duration_s, t);
  CHECK(t.n_events > 1000);  // flicker and the moving background still make events
  CHECK(t.valid == 0);
  CHECK(t.human == 0);
  const SimSpec e = dataset_empty_member("train", 3, 1, 5.0);
  CHECK_FALSE(e.dancer);
  CHECK(e.name.rfind("train-empty-00003-", 0) == 0);
  CHECK(dataset_member("train", 3, 1, 5.0).dancer);  // the dancer members are unchanged
}

TEST_CASE("dataset: random looks give each training recording a new person and leave val, test and the rest as they were", "[sim]") {
  std::set<std::string> names;
  std::set<int> garments;
  double h_lo = 1e9, h_hi = 0;
  for (int i = 0; i < 60; ++i) {
    const SimSpec cast = dataset_member("train", i, 1, 5.0), rnd = dataset_member("train", i, 1, 5.0, true);
    CHECK(cast.looks_seed == 0);
    REQUIRE(rnd.looks_seed != 0);
    // Only the looks change: motion, timing, scene and seed are the cast draw's.
    CHECK(rnd.motion == cast.motion);
    CHECK(rnd.motion_offset_s == cast.motion_offset_s);
    CHECK(rnd.seed == cast.seed);
    CHECK(rnd.scene.view == cast.scene.view);
    CHECK(rnd.name.find(cast.character) == std::string::npos);
    const Character c = random_looks(character_by_name(rnd.character), rnd.looks_seed);
    CHECK(c.name == looks_name(rnd.looks_seed));
    CHECK(rnd.name.find("-" + c.name + "-") != std::string::npos);
    names.insert(c.name);
    garments.insert(int(c.clothing));
    h_lo = std::min(h_lo, c.shape.height_mm), h_hi = std::max(h_hi, c.shape.height_mm);
    for (const Material* m : {&c.top, &c.bottom, &c.hat_material}) {
      CHECK(m->albedo >= 0.02f);
      CHECK(m->albedo <= 0.85f);
      if (m->pattern != Pattern::plain) CHECK(std::abs(m->albedo - m->albedo2) >= 0.2f - 1e-6f);
    }
  }
  CHECK(names.size() == 60);
  CHECK(garments.size() == 5);
  CHECK(h_lo < 1600);
  CHECK(h_hi > 1850);
  // The held-out splits keep their cast, so validation still measures unseen bodies.
  for (const char* split : {"val", "test"}) {
    const SimSpec a = dataset_member(split, 3, 1, 5.0), b = dataset_member(split, 3, 1, 5.0, true);
    CHECK(b.looks_seed == 0);
    CHECK(a.name == b.name);
  }
  // A simulator with looks renders them and says so.
  const Simulator s(dataset_member("train", 5, 1, 0.5, true));
  CHECK(s.character().name.rfind("r", 0) == 0);
  CHECK(s.description_json().find("\"looks_seed\"") != std::string::npos);
}

TEST_CASE("dataset: a framed dancer faces the view at the start and stays in the picture, wherever the clip starts", "[sim]") {
  // Members of the val split start late in their clips (the last 15%): unframed, several
  // leave the mocap subject out of the picture for the whole recording.
  double valid_unframed = 0, valid_framed = 0;
  int n = 0;
  for (int i = 0; i < 16; ++i) {
    const SimSpec u = dataset_member("val", i, 1, 5.0), f = dataset_member("val", i, 1, 5.0, false, true);
    CHECK(f.seed == u.seed);
    CHECK(f.motion_offset_s == u.motion_offset_s);
    const Simulator su(u), sf(f);
    // Facing the camera, a dancer's left hip is on the camera's right (+x); from behind, on its left.
    const Label l0 = sf.label_at(0);
    const double lr = l0.joints_mm[6].x() - l0.joints_mm[5].x();  // hipL - hipR
    if (f.scene.view == View::front) CHECK(lr > 0);
    if (f.scene.view == View::back) CHECK(lr < 0);
    for (int k = 0; k < 25; ++k) {
      const double t = 5.0 * (k + 0.5) / 25;
      const Label lu = su.label_at(t), lf = sf.label_at(t);
      for (int j = 0; j < kJointCount; ++j) valid_unframed += lu.valid[j], valid_framed += lf.valid[j];
      n += kJointCount;
    }
    // The motion itself is untouched: the same pose up to a turn and a shift (bone lengths equal).
    const Label a = su.label_at(1.0), b = sf.label_at(1.0);
    CHECK((a.joints_mm[1] - a.joints_mm[7]).norm() == Approx((b.joints_mm[1] - b.joints_mm[7]).norm()).epsilon(1e-9));
  }
  CHECK(valid_unframed / n < 0.8);
  CHECK(valid_framed / n > 0.95);
}

TEST_CASE("dataset: furnished rooms are seeded empty scenes, mostly filmed by a sweeping camera, and change no other member", "[sim]") {
  const SimSpec a = dataset_room_member("train", 5, 1, 5.0), b = dataset_room_member("train", 5, 1, 5.0);
  CHECK(a.name == b.name);
  CHECK(a.seed == b.seed);
  CHECK(a.name.rfind("train-room-00005-", 0) == 0);
  CHECK(a.name.find("-clutter") != std::string::npos);
  CHECK(dataset_room_member("train", 5, 2, 5.0).seed != a.seed);
  CHECK(dataset_room_member("val", 5, 1, 5.0).seed != a.seed);
  std::map<std::string, int> motions;
  std::set<std::string> views;
  for (int i = 0; i < 200; ++i) {
    const SimSpec m = dataset_room_member("val", i, 1, 5.0);
    CHECK_FALSE(m.dancer);
    CHECK(m.scene.clutter);
    CHECK(m.name.rfind("val-room-", 0) == 0);
    ++motions[camera_motion_name(m.scene.camera_motion)];
    views.insert(view_name(m.scene.view));
    // Its name says how the camera moves, as the presence report reads it.
    if (m.scene.camera_motion != SceneConfig::still)
      CHECK(m.name.size() > m.name.rfind(std::string("-") + camera_motion_name(m.scene.camera_motion)));
  }
  CHECK(views.size() == 4);
  CHECK(motions["sweep"] > 90);
  CHECK(motions["still"] > 10);
  CHECK(motions["pan"] > 10);
  CHECK(motions["shake"] > 5);
  // The older members keep their draws and names (rooms draw from their own stream).
  CHECK(dataset_empty_member("train", 3, 1, 5.0).name.find("clutter") == std::string::npos);
  CHECK(dataset_member("train", 3, 1, 5.0).name == dataset_member("train", 3, 1, 5.0).name);
  // Presets and scene JSON reach both options; an unknown camera motion is refused.
  const SimSpec p = preset_spec("front-high-static-clutter-sweep-empty");
  CHECK(p.scene.clutter);
  CHECK(p.scene.camera_motion == SceneConfig::sweep);
  CHECK_FALSE(p.dancer);
  const SimSpec j = spec_from_json(R"({"preset": "front-high-static", "clutter": true, "camera_motion": "sweep"})", "test");
  CHECK(j.scene.clutter);
  CHECK(j.scene.camera_motion == SceneConfig::sweep);
  CHECK_THROWS_WITH(spec_from_json(R"({"preset": "front-high-static", "camera_motion": "orbit"})", "test"),
                    Catch::Contains("still|pan|shake|sweep"));
}

TEST_CASE("dataset: dancers in furnished rooms are drawn as dancers, from their own stream, and change no other member", "[sim]") {
  std::map<std::string, int> motions;
  std::set<std::string> views;
  int val_segment = 0;
  for (int i = 0; i < 200; ++i) {
    const SimSpec m = dataset_dancer_room_member("val", i, 1, 5.0, true, true);
    CHECK(m.dancer);
    CHECK(m.scene.clutter);
    CHECK(m.frame_dancer);
    CHECK(m.name.rfind("val-dancer-room-" + std::string(i < 10 ? "0000" : i < 100 ? "000" : "00") + std::to_string(i) + "-", 0) == 0);
    CHECK(m.name.find("-clutter") != std::string::npos);
    // Validation keeps its held-out cast and the clips' last 15%.
    CHECK((m.character == "hana" || m.character == "eli"));
    CHECK(m.looks_seed == 0);
    if (m.motion != "dance") {
      CHECK(m.motion_begin == Approx(0.85));
      ++val_segment;
    }
    ++motions[camera_motion_name(m.scene.camera_motion)];
    views.insert(view_name(m.scene.view));
  }
  CHECK(val_segment > 100);
  CHECK(views.size() == 4);
  CHECK(motions["still"] > 50);
  CHECK(motions["sweep"] > 30);
  CHECK(motions["pan"] > 10);
  CHECK(motions["shake"] > 10);
  // Training dancers in rooms get new looks and the clips' first 85%; seeded.
  const SimSpec a = dataset_dancer_room_member("train", 7, 1, 5.0, true, true);
  CHECK(a.name == dataset_dancer_room_member("train", 7, 1, 5.0, true, true).name);
  CHECK(a.looks_seed != 0);
  CHECK(a.name.rfind("train-dancer-room-00007-r", 0) == 0);
  CHECK(dataset_dancer_room_member("train", 7, 2, 5.0, true, true).seed != a.seed);
  // Their own stream: neither the scene nor the person is the plain member's of the same index.
  const SimSpec plain = dataset_member("train", 7, 1, 5.0, true, true);
  CHECK(plain.seed != a.seed);
  CHECK(plain.looks_seed != a.looks_seed);
  CHECK_FALSE(plain.scene.clutter);
  CHECK(plain.name.rfind("train-00007-", 0) == 0);
  CHECK_THROWS_AS(dataset_dancer_room_member("dev", 0, 1, 5.0), std::invalid_argument);
}

TEST_CASE("dataset: remixed arms keep every bone, take the arm's pose from its own time, and change nothing else", "[sim]") {
  SimSpec s = preset_spec("ben-05_04-front-high-static");
  s.duration_s = 1;
  s.frame_dancer = true;
  const Simulator plain(s);
  SimSpec r = s;
  r.arm_offset_s = {0.8, 1.7};
  const Simulator mixed(r);
  const BodyShape shape = mixed.character().shape;
  const auto bones = body_bones(shape);
  const auto motion = load_bvh_motion(yelan::test::shared_data_or_skip("mocap/05_04.bvh"), shape);
  double moved = 0;
  for (double t : {0.0, 0.3, 0.71}) {
    const Label a = plain.label_at(t), b = mixed.label_at(t);
    // head, hips, knees and feet are the body's; shoulders, elbows and hands move
    for (int j : {0, 5, 6, 9, 10, 11, 12}) CHECK((a.joints_mm[j] - b.joints_mm[j]).norm() < 1e-6);
    for (int j : {3, 4, 7, 8}) moved = std::max(moved, (a.joints_mm[j] - b.joints_mm[j]).norm());
  }
  CHECK(moved > 100);  // mm: poses the clip did not have at that instant
  // Each arm on its own: the left arm is the same whatever the right one does.
  SimSpec left_only = s;
  left_only.arm_offset_s = {0, 1.7};
  const Simulator lonely(left_only);
  for (double t : {0.1, 0.6}) {
    const Label a = lonely.label_at(t), b = mixed.label_at(t);
    for (int j : {4, 8}) CHECK((a.joints_mm[j] - b.joints_mm[j]).norm() < 1e-6);  // elbowL, handL
    CHECK((a.joints_mm[7] - b.joints_mm[7]).norm() > 1);                            // handR differs
  }
  // The transplant itself: rigid, the arm's own bend kept, the rest of the body untouched.
  for (double t : {0.5, 2.0, 4.5}) {
    const BodyPose body = motion->at(t), arms = motion->at(t + 1.3);
    for (int side : {0, 1}) {
      const BodyPose m = with_arm_from(body, arms, side);
      for (const Bone& bone : bones) CHECK(std::abs((m.p[bone.a] - m.p[bone.b]).norm() / bone.length_mm - 1) < 1e-9);
      const auto angle = [&](const BodyPose& p) {
        const Vec3 u = p.p[kShoulderR + side] - p.p[kElbowR + side], v = p.p[kWristR + side] - p.p[kElbowR + side];
        return std::acos(u.normalized().dot(v.normalized()));
      };
      CHECK(angle(m) == Approx(angle(arms)).margin(1e-9));
      for (int point = 0; point < kBodyPointCount; ++point) {
        const bool arm = point == kShoulderR + side || point == kElbowR + side || point == kWristR + side || point == kHandTipR + side;
        if (!arm) CHECK((m.p[point] - body.p[point]).norm() == 0);
      }
      const BodyPose same = with_arm_from(body, body, side);  // its own arm: itself
      for (int point = 0; point < kBodyPointCount; ++point) CHECK((same.p[point] - body.p[point]).norm() < 1e-9);
    }
  }
  CHECK_THROWS_AS(with_arm_from(motion->at(0), motion->at(1), 2), std::invalid_argument);
  // scene.json carries it; out of range is refused
  const SimSpec fromj = spec_from_json(R"({"preset": "ben-05_04-front-high-static", "arm_offset_s": [0.5, 2]})", "x.json");
  CHECK(fromj.arm_offset_s[0] == 0.5);
  CHECK(fromj.arm_offset_s[1] == 2);
  CHECK(nlohmann::json::parse(mixed.description_json()).at("arm_offset_s")[1] == 1.7);
  CHECK_FALSE(nlohmann::json::parse(plain.description_json()).contains("arm_offset_s"));
  CHECK_THROWS_WITH(spec_from_json(R"({"preset": "ben-05_04-front-high-static", "arm_offset_s": [0.5, 2, 3]})", "x.json"),
                    Catch::Contains("two numbers"));
  r.arm_offset_s = {-0.5, 1};
  CHECK_THROWS_AS(Simulator(r), std::invalid_argument);
  // The dataset draws it for a share of the training dancers only, from its own stream.
  int remixed = 0;
  for (int i = 0; i < 200; ++i) {
    SimSpec m = dataset_member("train", i, 1, 5.0, true, true);
    const SimSpec before = m;
    remix_member_arms(m, 1, i, false, 0.0);
    CHECK(m.name == before.name);
    remix_member_arms(m, 1, i, false, 0.5);
    if (m.arm_offset_s[0] != 0) {
      ++remixed;
      CHECK(m.name == before.name + "-remix");
      for (double o : m.arm_offset_s) CHECK((o >= 0.25 && o <= 3.0));
      CHECK(m.arm_offset_s[0] != m.arm_offset_s[1]);
    } else {
      CHECK(m.name == before.name);
    }
  }
  CHECK(remixed > 70);
  CHECK(remixed < 130);
  SimSpec m = dataset_member("train", 3, 1, 5.0, true, true);
  CHECK_THROWS_AS(remix_member_arms(m, 1, 3, false, 1.5), std::invalid_argument);
}

TEST_CASE("dataset: --only makes the members of the named conditions alone, each as it is without --only", "[sim]") {
  CHECK(scene_matches({"front", "low", "static", "clutter", "sweep"}, {"low-sweep"}));
  CHECK_FALSE(scene_matches({"front", "high", "static", "clutter", "sweep"}, {"low-sweep"}));
  CHECK(scene_matches({"front", "high", "static", "flicker"}, {"low-sweep", "flicker"}));
  CHECK(scene_matches({"left", "medium", "dynamic"}, {}));
  CHECK(scene_matches({"left", "medium", "dynamic"}, {"still"}));
  CHECK_FALSE(scene_matches({"left", "medium", "dynamic", "pan"}, {"still"}));
  CHECK_THROWS_WITH(scene_matches({"front"}, {"dim-sweep"}), Catch::Contains("'dim'"));
  CHECK_THROWS_WITH(scene_matches({"front"}, {""}), Catch::Contains("no scene word"));
  // The words are the name's: view, light, background, then what the scene has.
  const SimSpec r = dataset_room_member("train", 3, 7, 0.5);
  const std::vector<std::string> w = scene_words(r);
  REQUIRE(w.size() >= 4);
  CHECK(r.name.ends_with(w.back()));
  CHECK(std::find(w.begin(), w.end(), "clutter") != w.end());
  // Every word a member's name holds is one --only knows, and the error lists them all.
  const std::vector<std::string>& vocabulary = scene_vocabulary();
  std::set<std::string> seen;
  for (int i = 0; i < 64; ++i)
    for (const SimSpec& m : {dataset_room_member("train", i, 7, 0.5), dataset_empty_member("val", i, 7, 0.5),
                             dataset_dancer_room_member("train", i, 7, 0.5)})
      for (const std::string& x : scene_words(m)) {
        INFO(m.name);
        CHECK(std::find(vocabulary.begin(), vocabulary.end(), x) != vocabulary.end());
        seen.insert(x);
      }
  CHECK(seen.size() + 1 == vocabulary.size());  // all drawn but "still", which no name holds
  try {
    scene_matches({"front"}, {"dim"});
    FAIL("an unknown word is accepted");
  } catch (const std::invalid_argument& e) {
    for (const std::string& x : vocabulary) CHECK_THAT(e.what(), Catch::Contains(" " + x));
  }

  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("yelan-dataset-only-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  DatasetSpec d;
  d.out_dir = dir.string();
  d.seed = 7;
  d.train = d.val = d.test = 0;
  d.train_rooms = 8;
  d.duration_s = 0.5;
  d.threads = 2;
  d.only = {"sweep"};
  int sweeping = 0;
  for (int i = 0; i < d.train_rooms; ++i) sweeping += dataset_room_member("train", i, 7, 0.5).name.ends_with("-sweep");
  REQUIRE(sweeping > 0);
  REQUIRE(sweeping < d.train_rooms);  // the seed draws both kinds, or the test proves nothing
  std::ostringstream log;
  CHECK(make_dataset(d, log) == sweeping);
  for (int i = 0; i < d.train_rooms; ++i) {
    const SimSpec m = dataset_room_member("train", i, 7, 0.5);
    CHECK(std::filesystem::exists(dir / "train" / dataset_file_name(m)) == m.name.ends_with("-sweep"));
  }
  std::ifstream in(dir / "manifest.json");
  const nlohmann::json man = nlohmann::json::parse(in);
  CHECK(man["only"] == nlohmann::json::array({"sweep"}));
  CHECK(man["recordings"].size() == std::size_t(sweeping));
  d.only = {"sweep-dim"};
  CHECK_THROWS_WITH(make_dataset(d, log), Catch::Contains("'dim'"));
  std::filesystem::remove_all(dir);
}
