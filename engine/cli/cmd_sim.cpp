// `yelan sim`: the motion-to-event simulator (camera/sim) from the command line: one
// recording from a preset or a scene.json, or a whole grid of them with a manifest.
#include <omp.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include "camera/io/event_writer.h"
#include "camera/sim/dataset.h"
#include "camera/sim/preview.h"
#include "camera/sim/presets.h"
#include "camera/sim/rng.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/train/evaluate.h"

namespace yelan::cli {
namespace {

namespace sim = camera::sim;

std::vector<std::string> csv(const std::optional<std::string>& s) { return s ? split_list(*s) : std::vector<std::string>{}; }

// A grid member's seed: stable under filtering and reordering of the grid.
std::uint64_t member_seed(std::uint64_t seed, const std::string& name) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ull;
  return sim::hash64(seed, h, 0) & 0xffffffffffffull;
}

struct Progress {
  std::ostream* err;
  bool tty;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
};

void show_progress(double t, double total, void* ctx) {
  auto* p = static_cast<Progress*>(ctx);
  if (!p->tty) return;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - p->start).count();
  const int width = 30, filled = int(t / total * width + 0.5);
  *p->err << "\r[" << std::string(std::size_t(filled), '#') << std::string(std::size_t(width - filled), ' ') << "] "
          << std::fixed << std::setprecision(2) << t << " / " << total << " s simulated, "
          << (wall > 0 ? t / wall : 0) << "x real time" << std::flush;
}

std::string stats_line(const sim::SimStats& s, double duration, double wall) {
  std::ostringstream o;
  o << s.events << " events (" << std::llround(double(s.events) / duration) << " ev/s), " << s.samples
    << " rendered keyframes (mean interval " << std::fixed << std::setprecision(3) << s.mean_step_s * 1e3 << " ms, min "
    << s.min_step_s * 1e3 << " ms), " << s.pixel_steps << " pixel steps (" << std::setprecision(0)
    << double(s.pixel_steps) / duration << " Hz), "
    << s.labels << " labels, " << s.masks << " masks; " << std::setprecision(2) << duration / wall
    << "x real time";
  return o.str();
}

int run_one(const sim::SimSpec& spec, const Args& a, std::ostream& out, std::ostream& err) {
  const auto outp = a.value("-o");
  if (!outp) throw UsageError("sim needs -o OUT.yelan.h5");
  if (camera::writer_format_for(*outp) != "yelan-h5") throw UsageError("-o " + *outp + ": expected a .yelan.h5 or .h5 path");
  Progress prog{&err, &err == &std::cerr && ::isatty(STDERR_FILENO) && !a.flag("--quiet")};
  const auto t0 = std::chrono::steady_clock::now();
  sim::Simulator s(spec);
  sim::RecordingWriter rec(*outp, s);
  std::optional<sim::PreviewSink> preview;
  if (const auto dir = a.value("--preview"))
    preview.emplace(*dir, s, a.int_value_or("--preview-every", 5, 1, 1000000), &rec);
  sim::run_to_end(s, preview ? static_cast<sim::SimSink&>(*preview) : rec, show_progress, &prog);
  rec.close();
  if (preview) {
    const auto files = preview->finish();
    err << files.size() << " pictures in " << *a.value("--preview") << " (contact_sheet.png, frame_<t_us>.png)\n";
  }
  const sim::SimStats stats = s.stats();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (prog.tty) err << "\n";
  out << *outp << ": " << stats_line(stats, spec.duration_s, wall) << "\n";
  return kOk;
}

// The benchmark split as files of preset names (one per line, '#' comments), so a run can
// name it (--sim @FILE) and anyone can diff it against what the simulator draws.
int write_splits(const std::string& dir, const Args& a, std::ostream& out) {
  const int seed = a.int_value_or("--seed", 1, 0, 1 << 30), scenes = a.int_value_or("--scenes", 48, 1, 1 << 20);
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& header, const std::vector<std::string>& names) {
    const std::string path = (std::filesystem::path(dir) / name).string();
    std::ostringstream f;
    f << header << "# regenerate: yelan sim --splits " << dir << " --seed " << seed << " --scenes " << scenes << "\n";
    for (const auto& n : names) f << n << "\n";
    camera::write_file_atomically(path, f.str());
    out << path << ": " << names.size() << " scenes\n";
  };
  write("train.txt", "# training split: the 11 training characters x the CMU train clips and procedural dances x\n"
                     "# 4 views x 3 lightings x 2 backgrounds (occlusion only as augmentation)\n", sim::grid_presets("train"));
  write("test.txt", "# test split: held-out characters (jade, kurt, lena) x held-out clips and procedural dances x\n"
                    "# 4 views x 3 lightings x 2 backgrounds x clear/occluded\n", sim::grid_presets("test"));
  write("test-seed" + std::to_string(seed) + "-" + std::to_string(scenes) + ".txt",
        "# the scenes of: yelan eval --sim test --seed " + std::to_string(seed) + " --scenes " + std::to_string(scenes) +
            " (conditions in turn, members drawn with the seed)\n",
        train::draw_test_scenes(std::uint64_t(seed), scenes));
  return kOk;
}

int run_grid(const std::string& which, const Args& a, std::ostream& out, std::ostream& err) {
  const auto dir = a.value("--out-dir");
  if (!dir) throw UsageError("sim --grid needs --out-dir DIR");
  sim::GridFilter f{csv(a.value("--characters")), csv(a.value("--motions")), csv(a.value("--views")),
                    csv(a.value("--lights")), csv(a.value("--backgrounds"))};
  std::vector<std::string> names = sim::grid_presets(which, f);
  const int limit = a.int_value_or("--limit", int(names.size()), 0, 1 << 30);
  if (int(names.size()) > limit) names.resize(std::size_t(limit));
  if (names.empty()) throw UsageError("sim --grid " + which + ": the filters leave no scene");
  const double duration = parse_duration_s(a.value_or("--duration", "2s"));
  const std::uint64_t seed = a.u64_value_or("--seed", 1, (1ull << 48) - 1);
  std::filesystem::create_directories(*dir);
  std::ostringstream manifest;
  manifest << "{\"format\": \"yelan-sim-manifest\", \"grid\": \"" << which << "\", \"seed\": " << seed
           << ", \"duration_s\": " << duration << ", \"recordings\": [";
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < names.size(); ++i) {
    sim::SimSpec spec = sim::preset_spec(names[i]);
    spec.duration_s = duration;
    spec.seed = member_seed(seed, names[i]);
    const std::string file = names[i] + ".yelan.h5";
    const std::string path = (std::filesystem::path(*dir) / file).string();
    std::string status = "existing";
    if (!std::filesystem::exists(path) || a.flag("--force")) {
      const auto t0 = std::chrono::steady_clock::now();
      const sim::SimStats s = sim::write_recording(spec, path);
      status = stats_line(s, duration, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double eta = wall / double(i + 1) * double(names.size() - i - 1);
    err << "[" << (i + 1) << "/" << names.size() << "] " << names[i] << ": " << status << "; ETA " << std::llround(eta)
        << " s\n";
    manifest << (i ? ", " : "") << "{\"file\": \"" << file << "\", \"preset\": \"" << names[i] << "\", \"seed\": "
             << spec.seed << ", \"split\": \"" << (sim::character_by_name(spec.character).test_only ? "test" : "train")
             << "\"}";
  }
  manifest << "]}\n";
  const std::string mpath = (std::filesystem::path(*dir) / "manifest.json").string();
  camera::write_file_atomically(mpath, manifest.str());
  out << names.size() << " recordings in " << *dir << ", manifest " << mpath << "\n";
  return kOk;
}

// `yelan sim --dataset DIR`: train / val / test recordings drawn with augmentation
// (camera/sim/dataset.h), in parallel, resumable.
int run_dataset(const std::string& dir, const Args& a, std::ostream& out, std::ostream& err) {
  sim::DatasetSpec d;
  d.out_dir = dir;
  d.seed = a.u64_value_or("--seed", 1, (1ull << 48) - 1);
  d.train = a.int_value_or("--train", d.train, 0, 1 << 20);
  d.val = a.int_value_or("--val", d.val, 0, 1 << 20);
  d.test = a.int_value_or("--test", d.test, 0, 1 << 20);
  d.train_empty = a.int_value_or("--train-empty", 0, 0, 1 << 20);
  d.val_empty = a.int_value_or("--val-empty", 0, 0, 1 << 20);
  d.test_empty = a.int_value_or("--test-empty", 0, 0, 1 << 20);
  d.train_rooms = a.int_value_or("--train-rooms", 0, 0, 1 << 20);
  d.val_rooms = a.int_value_or("--val-rooms", 0, 0, 1 << 20);
  d.test_rooms = a.int_value_or("--test-rooms", 0, 0, 1 << 20);
  d.train_dancer_rooms = a.int_value_or("--train-dancer-rooms", 0, 0, 1 << 20);
  d.val_dancer_rooms = a.int_value_or("--val-dancer-rooms", 0, 0, 1 << 20);
  d.test_dancer_rooms = a.int_value_or("--test-dancer-rooms", 0, 0, 1 << 20);
  d.duration_s = parse_duration_s(a.value_or("--duration", "5s"));
  d.random_looks = a.flag("--random-looks");
  d.frame_dancer = a.flag("--frame-dancer");
  if (a.value("--low-light-dn")) d.low_light_dn = a.number_or("--low-light-dn", 20, 1e-3, 1e5);
  d.remix_arms = a.number_or("--remix-arms", 0, 0, 1);
  d.free_arms = a.number_or("--free-arms", 0, 0, 1);
  if (const auto fp = a.value("--front-print"); fp && fp->find('-', 1) != std::string::npos) {
    // A range A-B: each dancer recording draws its own scale.
    const std::size_t dash = fp->find('-', 1);
    const std::string bad = "--front-print: expected S or A-B with 0 <= A < B <= 3, got '" + *fp + "'";
    const auto end = [&](const std::string& t) {
      std::size_t used = 0;
      double v = -1;
      try {
        v = std::stod(t, &used);
      } catch (const std::exception&) {
      }
      if (used != t.size() || !(v >= 0 && v <= 3)) throw UsageError(bad);
      return v;
    };
    d.front_print = end(fp->substr(0, dash));
    d.front_print_max = end(fp->substr(dash + 1));
    if (!(d.front_print_max > d.front_print)) throw UsageError(bad);
  } else {
    d.front_print = d.front_print_max = a.number_or("--front-print", 1, 0, 3);
  }
  if (const auto only = a.value("--only")) {
    std::istringstream in(*only);
    for (std::string c; std::getline(in, c, ',');) d.only.push_back(c);
    if (d.only.empty()) throw UsageError("--only: expected conditions such as low-sweep,flicker");
  }
  d.threads = a.int_value_or("--threads", 0, 0, 256);
  d.progress_tty = &err == &std::cerr && ::isatty(STDERR_FILENO) && !a.flag("--quiet");
  try {
    const auto t0 = std::chrono::steady_clock::now();
    const int made = sim::make_dataset(d, err);
    out << dir << ": " << d.train << " train, " << d.val << " val, " << d.test << " test recordings, "
        << d.train_dancer_rooms + d.val_dancer_rooms + d.test_dancer_rooms << " dancers in furnished rooms and "
        << d.train_empty + d.val_empty + d.test_empty + d.train_rooms + d.val_rooms + d.test_rooms << " without a dancer (" << made
        << " simulated now in " << std::llround(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count())
        << " s), manifest " << (std::filesystem::path(dir) / "manifest.json").string() << "\n";
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return kOk;
}

int list(std::ostream& out) {
  out << "characters (name, height, clothing, split):\n";
  for (const auto& c : sim::characters())
    out << "  " << std::left << std::setw(8) << c.name << std::right << std::setw(6) << c.shape.height_mm << " mm  "
        << std::left << std::setw(12) << sim::clothing_name(c.clothing) << (c.test_only ? "test" : "train") << "\n";
  out << "motions: train";
  for (const auto& m : sim::train_motions()) out << " " << m;
  out << "; test";
  for (const auto& m : sim::test_motions()) out << " " << m;
  out << "; procedural: dance, dance<N>\n"
      << "presets: <character>-<motion>-<view>-<light>-<bg> (e.g. ana-05_04-front-high-static) or\n"
      << "  <view>-<light>-<bg> (e.g. front-high-static, front-low-dynamic), optionally with -occluded, -flicker;\n"
      << "  views front back left right; lights high medium low; backgrounds static dynamic\n"
      << "grid: train " << sim::grid_presets("train").size() << " scenes, test " << sim::grid_presets("test").size()
      << " scenes\n";
  return kOk;
}

}  // namespace

int cmd_sim(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  const Args a("sim", argv,
               {"--preset", "--config", "--seed", "--duration", "-o", "--preview", "--preview-every", "--threads",
                "--grid", "--out-dir", "--characters", "--motions", "--views", "--lights", "--backgrounds", "--limit", "--splits", "--scenes",
                "--dataset", "--train", "--val", "--test", "--train-empty", "--val-empty", "--test-empty", "--low-light-dn", "--remix-arms", "--free-arms",
                "--front-print", "--only",
                "--train-rooms", "--val-rooms", "--test-rooms", "--train-dancer-rooms", "--val-dancer-rooms",
                "--test-dancer-rooms"},
               {"--list", "--quiet", "--force", "--random-looks", "--frame-dancer"});
  a.expect_positionals(0, 0);
  if (a.value("--threads")) omp_set_num_threads(a.int_value_or("--threads", 1, 1, 256));
  if (a.flag("--list")) return list(out);
  if (const auto g = a.value("--grid")) return run_grid(*g, a, out, err);
  if (const auto d = a.value("--splits")) return write_splits(*d, a, out);
  if (const auto d = a.value("--dataset")) return run_dataset(*d, a, out, err);
  const auto preset = a.value("--preset"), config = a.value("--config");
  if (bool(preset) == bool(config)) throw UsageError("sim needs exactly one of --preset NAME and --config scene.json");
  if (const auto o = a.value("-o")) check_output("-o", *o, {config.value_or("")});
  sim::SimSpec spec;
  if (preset) {
    spec = sim::preset_spec(*preset);
  } else {
    std::ifstream in(*config);
    if (!in) throw UsageError("--config " + *config + ": cannot read");
    std::stringstream text;
    text << in.rdbuf();
    spec = sim::spec_from_json(text.str(), *config);
    if (spec.name.empty()) spec.name = std::filesystem::path(*config).stem().string();
  }
  spec.seed = a.u64_value_or("--seed", spec.seed, (1ull << 48) - 1);
  if (const auto d = a.value("--duration")) spec.duration_s = parse_duration_s(*d);
  return run_one(spec, a, out, err);
}

}  // namespace yelan::cli
