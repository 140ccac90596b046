#include "camera/sim/dataset.h"

#include <omp.h>
#include <signal.h>

#include <cerrno>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "camera/io/event_writer.h"
#include "camera/sim/presets.h"
#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace fs = std::filesystem;

namespace {

// Validation holds out one woman and one man of the training cast.
const std::vector<std::string> kValCharacters = {"hana", "eli"};
// Training clips give their first 85% to training, the rest to validation.
constexpr double kTrainSegmentEnd = 0.85;

std::uint64_t split_stream(const std::string& split) {
  return split == "train" ? 0x7a1 : split == "val" ? 0x7a2 : 0x7a3;
}

template <class T>
const T& pick(Rng& r, const std::vector<T>& v) {
  return v[std::size_t(r.below(int(v.size())))];
}

// How a split draws its camera and scene (the draws' order is part of the dataset's
// definition: member i's files depend on it).
struct SceneDraw {
  double yaw_jitter_deg, distance_lo, distance_hi, height_lo, height_hi;
  double high_below, medium_below;  // lighting: high if u < high_below, medium if < medium_below
  double dynamic_p, flicker_p, occluders_p;
};

void draw_scene(Rng& r, const SceneDraw& d, double duration_s, SimSpec& s) {
  const View views[4] = {View::front, View::back, View::left, View::right};
  s.scene.view = views[r.below(4)];
  s.scene.yaw_deg = view_yaw_deg(s.scene.view) + r.uniform(-d.yaw_jitter_deg, d.yaw_jitter_deg);
  s.scene.distance_mm = r.uniform(d.distance_lo, d.distance_hi);
  s.scene.height_mm = r.uniform(d.height_lo, d.height_hi);
  const double l = r.uniform();
  s.scene.light = l < d.high_below ? LightLevel::high : l < d.medium_below ? LightLevel::medium : LightLevel::low;
  s.scene.background = r.uniform() < d.dynamic_p ? SceneConfig::dynamic : SceneConfig::static_wall;
  s.scene.flicker = r.uniform() < d.flicker_p;
  s.scene.occluders = r.uniform() < d.occluders_p;
  s.duration_s = duration_s;
  s.seed = r.bits() & 0xffffffffffffull;
}

// The scene words that no name function of scene.h gives; scene_suffix and scene_vocabulary
// read them here alone.
constexpr const char* kStaticWord = "static";
constexpr const char* kDynamicWord = "dynamic";
constexpr const char* kOccludedWord = "occluded";
constexpr const char* kFlickerWord = "flicker";
constexpr const char* kClutterWord = "clutter";

std::string and_word(bool on, const char* word) { return on ? std::string("-") + word : std::string(); }

// "<view>-<light>-<bg>[-occluded][-flicker][-clutter][-pan|-shake|-sweep]"
std::string scene_suffix(const SimSpec& s) {
  return std::string(view_name(s.scene.view)) + "-" + light_name(s.scene.light) + "-" +
         (s.scene.background == SceneConfig::dynamic ? kDynamicWord : kStaticWord) +
         and_word(s.scene.occluders, kOccludedWord) + and_word(s.scene.flicker, kFlickerWord) +
         and_word(s.scene.clutter, kClutterWord) +
         and_word(s.scene.camera_motion != SceneConfig::still, camera_motion_name(s.scene.camera_motion));
}

}  // namespace

const std::vector<std::string>& dataset_characters(const std::string& split) {
  static const std::vector<std::string> train = [] {
    std::vector<std::string> out;
    for (const auto& c : characters())
      if (!c.test_only && std::find(kValCharacters.begin(), kValCharacters.end(), c.name) == kValCharacters.end())
        out.push_back(c.name);
    return out;
  }();
  static const std::vector<std::string> test = [] {
    std::vector<std::string> out;
    for (const auto& c : characters())
      if (c.test_only) out.push_back(c.name);
    return out;
  }();
  if (split == "train") return train;
  if (split == "val") return kValCharacters;
  if (split == "test") return test;
  throw std::invalid_argument("dataset split '" + split + "': expected train, val or test");
}

namespace {

// A dancer of the split drawn from `stream` (the plain members': split_stream(split), looks
// 0x100c), named <split>-[<kind>-]NNNNN-<who>-<motion>-<scene>. A furnished member draws its
// camera's motion after everything else, from the same stream.
SimSpec dancer_member(const std::string& split, int i, std::uint64_t seed, double duration_s, bool random_looks,
                      bool frame_dancer, std::uint64_t stream, std::uint64_t looks_stream, const char* kind,
                      bool furnished) {
  const std::vector<std::string>& cast = dataset_characters(split);
  const bool test = split == "test";
  Rng r(hash64(seed, stream, std::uint64_t(i)), 0xda7a);
  SimSpec s;
  s.character = pick(r, cast);
  const std::vector<std::string>& clips = test ? test_motions() : train_motions();
  const bool dance = r.uniform() < 0.25;
  s.motion = dance ? "dance" : pick(r, clips);
  s.motion_options.mirror = r.uniform() < 0.5;
  s.motion_options.speed = r.uniform(0.7, 1.4);
  if (!dance && split == "train") s.motion_end = kTrainSegmentEnd;
  if (!dance && split == "val") s.motion_begin = kTrainSegmentEnd;
  // Where in the (warped) segment the recording starts: anywhere. The clip's length is known
  // only once loaded, so the offset is a fraction resolved by the simulator's ping-pong
  // (an offset past the segment's end plays it backwards, still inside the segment).
  s.motion_offset_s = dance ? 0 : r.uniform(0, 12.0);
  s.height_scale = r.uniform(0.94, 1.06);
  s.girth_scale = r.uniform(0.9, 1.12);
  if (r.uniform() < 0.3) s.clothing = Clothing(r.below(5));
  draw_scene(r, {25, 2800, 4600, 900, 1600, 0.4, 0.75, 0.5, 0.15, 0.15}, duration_s, s);
  if (furnished) {
    // A dance game's camera mostly stands on a shelf; some are held or knocked.
    const double u = r.uniform();
    s.scene.clutter = true;
    s.scene.camera_motion = u < 0.4 ? SceneConfig::still : u < 0.55 ? SceneConfig::pan
                          : u < 0.7 ? SceneConfig::shake : SceneConfig::sweep;
  }
  // Its own stream, so the draws above stay what they were without random looks.
  if (random_looks && split == "train") s.looks_seed = hash64(seed, looks_stream, std::uint64_t(i)) | 1;
  s.frame_dancer = frame_dancer;
  std::ostringstream name;
  name << split << "-" << (*kind ? std::string(kind) + "-" : "") << std::setw(5) << std::setfill('0') << i << "-"
       << (s.looks_seed ? looks_name(s.looks_seed) : s.character) << "-" << s.motion << "-" << scene_suffix(s);
  s.name = name.str();
  return s;
}

}  // namespace

SimSpec dataset_member(const std::string& split, int i, std::uint64_t seed, double duration_s, bool random_looks,
                       bool frame_dancer) {
  return dancer_member(split, i, seed, duration_s, random_looks, frame_dancer, split_stream(split), 0x100c, "", false);
}

SimSpec dataset_dancer_room_member(const std::string& split, int i, std::uint64_t seed, double duration_s,
                                   bool random_looks, bool frame_dancer) {
  dataset_characters(split);  // checks the split's name before its stream is derived
  return dancer_member(split, i, seed, duration_s, random_looks, frame_dancer, split_stream(split) ^ 0xd007,
                       0x100c ^ 0xd007, "dancer-room", true);
}

namespace {

// A scene with nobody in it, named <split>-<kind>-NNNNN-<scene>, drawn from its own stream.
// The camera's motion is drawn after the scene (`camera` maps that draw to a motion), so the
// still-camera empty scenes stayed what they were when camera motion came.
SimSpec nobody_member(const std::string& split, int i, std::uint64_t seed, double duration_s, const char* kind,
                      std::uint64_t stream, std::uint64_t tag, double dynamic_p, bool clutter,
                      SceneConfig::CameraMotion (*camera)(double)) {
  dataset_characters(split);  // checks the split's name
  Rng r(hash64(seed, split_stream(split) ^ stream, std::uint64_t(i)), tag);
  SimSpec s;
  s.dancer = false;
  s.motion = "dance";  // moves nothing visible; keeps the sampling rate of a scene with motion
  draw_scene(r, {45, 2500, 5000, 800, 1800, 0.34, 0.67, dynamic_p, 0.5, 0.3}, duration_s, s);
  s.scene.clutter = clutter;
  s.scene.camera_motion = camera(r.uniform());
  std::ostringstream name;
  name << split << "-" << kind << "-" << std::setw(5) << std::setfill('0') << i << "-" << scene_suffix(s);
  s.name = name.str();
  return s;
}

}  // namespace

SimSpec dataset_empty_member(const std::string& split, int i, std::uint64_t seed, double duration_s) {
  return nobody_member(split, i, seed, duration_s, "empty", 0xe3e3, 0xe3e7, 0.7, false, [](double u) {
    return u < 0.4 ? SceneConfig::still : u < 0.7 ? SceneConfig::pan : SceneConfig::shake;
  });
}

SimSpec dataset_room_member(const std::string& split, int i, std::uint64_t seed, double duration_s) {
  return nobody_member(split, i, seed, duration_s, "room", 0x7007, 0x7009, 0.5, true, [](double u) {
    return u < 0.15 ? SceneConfig::still : u < 0.3 ? SceneConfig::pan : u < 0.4 ? SceneConfig::shake : SceneConfig::sweep;
  });
}

std::string dataset_file_name(const SimSpec& spec) { return spec.name + ".yelan.h5"; }

std::vector<std::string> scene_words(const SimSpec& spec) {
  std::vector<std::string> out;
  std::istringstream in(scene_suffix(spec));
  for (std::string w; std::getline(in, w, '-');) out.push_back(w);
  return out;
}

const std::vector<std::string>& scene_vocabulary() {
  static const std::vector<std::string> words = [] {
    std::vector<std::string> out;
    for (View v : {View::front, View::back, View::left, View::right}) out.push_back(view_name(v));
    for (LightLevel l : {LightLevel::high, LightLevel::medium, LightLevel::low}) out.push_back(light_name(l));
    out.insert(out.end(), {kStaticWord, kDynamicWord, kOccludedWord, kFlickerWord, kClutterWord});
    for (int m : {SceneConfig::still, SceneConfig::pan, SceneConfig::shake, SceneConfig::sweep})
      out.push_back(camera_motion_name(m));
    return out;
  }();
  return words;
}

bool scene_matches(const std::vector<std::string>& words, const std::vector<std::string>& only) {
  const std::vector<std::string>& known = scene_vocabulary();
  bool any = only.empty();
  for (const std::string& cond : only) {
    bool all = true;
    std::istringstream in(cond);
    std::string w;
    int n = 0;
    while (std::getline(in, w, '-')) {
      ++n;
      if (std::find(known.begin(), known.end(), w) == known.end()) {
        std::string list;
        for (const std::string& k : known) list += (list.empty() ? "" : " ") + k;
        throw std::invalid_argument("dataset condition '" + cond + "': unknown scene word '" + w + "' (expected words of " +
                                    list + ", joined by '-')");
      }
      // A still camera is the absence of a motion word in the name.
      const auto moving = [](const std::string& x) {
        return x == camera_motion_name(SceneConfig::pan) || x == camera_motion_name(SceneConfig::shake) ||
               x == camera_motion_name(SceneConfig::sweep);
      };
      const bool has = w == camera_motion_name(SceneConfig::still) ? std::none_of(words.begin(), words.end(), moving)
                                                                   : std::find(words.begin(), words.end(), w) != words.end();
      all = all && has;
    }
    if (n == 0) throw std::invalid_argument("dataset condition '" + cond + "': no scene word");
    any = any || all;
  }
  return any;
}

void remix_member_arms(SimSpec& s, std::uint64_t seed, int i, bool room, double p) {
  if (!(p >= 0 && p <= 1)) throw std::invalid_argument("dataset: the share of remixed arms must be in 0..1");
  if (p == 0 || !s.dancer) return;
  Rng r(hash64(seed, split_stream("train") ^ (room ? 0xa4e5d007ull : 0xa4e5ull), std::uint64_t(i)), 0x4e31);
  if (!(r.uniform() < p)) return;
  for (double& o : s.arm_offset_s) o = r.uniform(0.25, 3.0);
  s.name += "-remix";
}

void free_member_arms(SimSpec& s, std::uint64_t seed, int i, bool room, double p) {
  if (!(p >= 0 && p <= 1)) throw std::invalid_argument("dataset: the share of free arms must be in 0..1");
  if (p == 0 || !s.dancer || s.arm_offset_s[0] != 0 || s.arm_offset_s[1] != 0) return;
  Rng r(hash64(seed, split_stream("train") ^ (room ? 0xf4eed007ull : 0xf4eeull), std::uint64_t(i)), 0xf4e1);
  if (!(r.uniform() < p)) return;
  s.free_arms_seed = r.bits() | 1;
  s.name += "-free";
}

double member_front_print(const std::string& split, const SimSpec& s, std::uint64_t seed, double lo, double hi) {
  if (!(hi > lo) || !s.dancer) return lo;
  // Keyed by the member's split and name, not its index: the plain dancers and those in
  // furnished rooms share indices.
  std::uint64_t h = split_stream(split) ^ 0xf9a1;
  for (const unsigned char c : s.name) h = hash64(h, c, 0x9f);
  return lo + (hi - lo) * Rng(hash64(seed, h, 0xf9a2), 0xf9a3).uniform();
}

int make_dataset(const DatasetSpec& d, std::ostream& err) {
  if (d.out_dir.empty()) throw std::invalid_argument("dataset: no output folder");
  if (d.train < 0 || d.val < 0 || d.test < 0 || d.train_empty < 0 || d.val_empty < 0 || d.test_empty < 0 ||
      d.train_rooms < 0 || d.val_rooms < 0 || d.test_rooms < 0 || d.train_dancer_rooms < 0 || d.val_dancer_rooms < 0 ||
      d.test_dancer_rooms < 0 ||
      d.train + d.val + d.test + d.train_empty + d.val_empty + d.test_empty + d.train_rooms + d.val_rooms + d.test_rooms +
              d.train_dancer_rooms + d.val_dancer_rooms + d.test_dancer_rooms ==
          0)
    throw std::invalid_argument("dataset: need a non-negative count per split, and at least one recording");
  if (!(d.duration_s >= 0.5 && d.duration_s <= 600)) throw std::invalid_argument("dataset: duration must be 0.5-600 s");
  if (d.low_light_dn && !(*d.low_light_dn > 0 && *d.low_light_dn <= 1e5))
    throw std::invalid_argument("dataset: low light must be in (0, 1e5] DN");
  // Low light is not in the files' names: adding to a dataset drawn at another level would
  // mix two lightings under one name. Manifests from before the key were drawn at 4 DN.
  const double low_dn = d.low_light_dn ? *d.low_light_dn : lighting(LightLevel::low, false).level;
  if (!(d.remix_arms >= 0 && d.remix_arms <= 1)) throw std::invalid_argument("dataset: the share of remixed arms must be in 0..1");
  if (!(d.free_arms >= 0 && d.free_arms <= 1)) throw std::invalid_argument("dataset: the share of free arms must be in 0..1");
  const double print_max = std::max(d.front_print, d.front_print_max);
  if (!(d.front_print >= 0 && print_max <= 3)) throw std::invalid_argument("dataset: the front print's scale must be in 0..3");
  if (const fs::path old = fs::path(d.out_dir) / "manifest.json"; fs::exists(old)) {
    std::ifstream in(old);
    nlohmann::json m;
    try {
      m = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
      throw std::runtime_error(old.string() + ": not a dataset manifest (" + e.what() + ")");
    }
    const double was = m.is_object() && m.contains("low_light_dn") && m["low_light_dn"].is_number()
                           ? m["low_light_dn"].get<double>()
                           : 4.0;
    if (was != low_dn) {
      std::ostringstream msg;
      msg << "dataset " << d.out_dir << " was drawn with low light at " << was << " DN (its manifest), this run would use "
          << low_dn << ": give --low-light-dn " << was << " to add to it, or another folder";
      throw std::invalid_argument(msg.str());
    }
    struct Share {
      const char *key, *flag;
      double asked, absent;
    };
    // The same for the remixed and free arms and the front cues (manifests from before a key
    // were drawn at its default).
    const auto drawn = [&m](const char* key, double absent) {
      return m.is_object() && m.contains(key) && m[key].is_number() ? m[key].get<double>() : absent;
    };
    const double was_print = drawn("front_print", 1.0);
    for (const Share& sh : {Share{"remix_arms", "--remix-arms", d.remix_arms, 0.0}, Share{"free_arms", "--free-arms", d.free_arms, 0.0},
                            Share{"front_print", "--front-print", d.front_print, 1.0},
                            Share{"front_print_max", "--front-print (its upper end)", print_max, was_print}}) {
      const double was_drawn = drawn(sh.key, sh.absent);
      if (was_drawn != sh.asked) {
        std::ostringstream msg;
        msg << "dataset " << d.out_dir << " was drawn with " << sh.flag << " " << was_drawn << " (its manifest), this run asks "
            << sh.asked << ": give the manifest's value to add to it, or another folder";
        throw std::invalid_argument(msg.str());
      }
    }
  }
  struct Job {
    std::string split;
    SimSpec spec;
    std::string path;
  };
  std::vector<Job> jobs;
  nlohmann::ordered_json manifest = {{"format", "yelan-dataset-manifest"},
                                     {"version", 1},
                                     {"seed", d.seed},
                                     {"duration_s", d.duration_s},
                                     {"looks", d.random_looks ? "random per training recording" : "the cast's"},
                                     {"frame_dancer", d.frame_dancer},
                                     {"low_light_dn", low_dn},
                                     {"remix_arms", d.remix_arms},
                                     {"free_arms", d.free_arms},
                                     {"front_print", d.front_print},
                                     {"front_print_max", print_max},
                                     {"counts", {{"train", d.train}, {"val", d.val}, {"test", d.test}}},
                                     {"empty_counts", {{"train", d.train_empty}, {"val", d.val_empty}, {"test", d.test_empty}}},
                                     {"room_counts", {{"train", d.train_rooms}, {"val", d.val_rooms}, {"test", d.test_rooms}}},
                                     {"dancer_room_counts",
                                      {{"train", d.train_dancer_rooms}, {"val", d.val_dancer_rooms}, {"test", d.test_dancer_rooms}}},
                                     {"characters",
                                      {{"train", dataset_characters("train")},
                                       {"val", dataset_characters("val")},
                                       {"test", dataset_characters("test")}}},
                                     {"train_segment", {0, kTrainSegmentEnd}},
                                     {"val_segment", {kTrainSegmentEnd, 1}},
                                     {"recordings", nlohmann::ordered_json::array()}};
  for (const auto& [split, n] : {std::pair<std::string, int>{"train", d.train}, {"val", d.val}, {"test", d.test}}) {
    fs::create_directories(fs::path(d.out_dir) / split);
    for (int i = 0; i < n; ++i) {
      Job j{split, dataset_member(split, i, d.seed, d.duration_s, d.random_looks, d.frame_dancer), ""};
      if (split == "train") {
        remix_member_arms(j.spec, d.seed, i, false, d.remix_arms);
        free_member_arms(j.spec, d.seed, i, false, d.free_arms);
      }
      j.path = (fs::path(d.out_dir) / split / dataset_file_name(j.spec)).string();
      jobs.push_back(j);
    }
    const int empty = split == "train" ? d.train_empty : split == "val" ? d.val_empty : d.test_empty;
    for (int i = 0; i < empty; ++i) {
      Job j{split, dataset_empty_member(split, i, d.seed, d.duration_s), ""};
      j.path = (fs::path(d.out_dir) / split / dataset_file_name(j.spec)).string();
      jobs.push_back(j);
    }
    const int rooms = split == "train" ? d.train_rooms : split == "val" ? d.val_rooms : d.test_rooms;
    for (int i = 0; i < rooms; ++i) {
      Job j{split, dataset_room_member(split, i, d.seed, d.duration_s), ""};
      j.path = (fs::path(d.out_dir) / split / dataset_file_name(j.spec)).string();
      jobs.push_back(j);
    }
    const int dancer_rooms = split == "train" ? d.train_dancer_rooms : split == "val" ? d.val_dancer_rooms : d.test_dancer_rooms;
    for (int i = 0; i < dancer_rooms; ++i) {
      Job j{split, dataset_dancer_room_member(split, i, d.seed, d.duration_s, d.random_looks, d.frame_dancer), ""};
      if (split == "train") {
        remix_member_arms(j.spec, d.seed, i, true, d.remix_arms);
        free_member_arms(j.spec, d.seed, i, true, d.free_arms);
      }
      j.path = (fs::path(d.out_dir) / split / dataset_file_name(j.spec)).string();
      jobs.push_back(j);
    }
  }
  for (Job& j : jobs) {
    set_low_light_dn(j.spec.scene, d.low_light_dn);
    j.spec.front_print = member_front_print(j.split, j.spec, d.seed, d.front_print, print_max);
  }
  if (!d.only.empty()) {
    scene_matches({}, d.only);  // every condition checked, even where no member is drawn
    std::erase_if(jobs, [&](const Job& j) { return !scene_matches(scene_words(j.spec), d.only); });
    manifest["only"] = d.only;
  }
  // Temporary files of a run that was killed (name.tmp-PID-XXXXXX, its process gone) are removed:
  // their recordings are simulated again.
  for (const char* split : {"train", "val", "test"}) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(d.out_dir) / split, ec)) {
      const std::string n = e.path().filename().string();
      const auto at = n.rfind(".tmp-");
      if (at == std::string::npos) continue;
      std::string pid = n.substr(at + 5);  // name.tmp-PID-XXXXXX
      pid = pid.substr(0, pid.find('-'));
      if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9) continue;
      if (::kill(pid_t(std::stol(pid)), 0) != 0 && errno == ESRCH) fs::remove(e.path(), ec);
    }
  }
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!fs::exists(jobs[i].path)) todo.push_back(i);
  err << jobs.size() << " recordings, " << (jobs.size() - todo.size()) << " already there, " << todo.size()
      << " to simulate (" << d.duration_s << " s each)\n";
  std::atomic<int> done{0};
  std::mutex mu;
  std::string failure;
  const auto start = std::chrono::steady_clock::now();
  const int threads = d.threads > 0 ? d.threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::size_t k = 0; k < todo.size(); ++k) {
    {
      std::lock_guard<std::mutex> lock(mu);
      if (!failure.empty()) continue;
    }
    const Job& j = jobs[todo[k]];
    try {
      write_recording(j.spec, j.path);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mu);
      if (failure.empty()) failure = j.path + ": " + e.what();
      continue;
    }
    const int n = ++done;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double eta = wall / n * double(todo.size() - std::size_t(n));
    std::lock_guard<std::mutex> lock(mu);
    if (d.progress_tty) {
      const int width = 30, filled = int(double(n) / double(todo.size()) * width);
      err << "\r[" << std::string(std::size_t(filled), '#') << std::string(std::size_t(width - filled), ' ') << "] " << n
          << "/" << todo.size() << "  " << std::fixed << std::setprecision(1) << wall / 60 << " min, ETA "
          << eta / 60 << " min   " << std::defaultfloat << std::flush;
    } else {
      err << "[" << n << "/" << todo.size() << "] " << j.spec.name << "; ETA " << std::llround(eta) << " s\n";
    }
  }
  if (d.progress_tty) err << "\n";
  if (!failure.empty()) throw std::runtime_error(failure);
  for (const Job& j : jobs) {
    const Simulator sim(j.spec);  // cheap without running: gives the scene's description
    manifest["recordings"].push_back({{"split", j.split},
                                      {"file", (fs::path(j.split) / dataset_file_name(j.spec)).string()},
                                      {"scene", nlohmann::json::parse(sim.description_json())}});
  }
  const std::string mpath = (fs::path(d.out_dir) / "manifest.json").string();
  TempFile tmp(mpath);
  {
    std::ofstream m(tmp.path());
    m << manifest.dump(1) << "\n";
    if (!m) throw std::runtime_error("cannot write " + tmp.path());
  }
  tmp.commit();
  return int(todo.size());
}

}  // namespace yelan::camera::sim
