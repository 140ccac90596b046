// `yelan run`: events from a file -> 3D poses (engine/run), written as CSV, JSON or HDF5.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>

#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "camera/io/format_error.h"
#include "camera/io/h5.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/run/pipeline.h"
#include "engine/run/viz.h"
#include "engine/threads.h"

namespace yelan::cli {
namespace {

void write_poses(const std::string& path, const std::vector<run::Pose>& poses) {
  const std::string ext = std::filesystem::path(path).extension().string();
  camera::TempFile tmp(path);
  if (ext == ".csv") {
    std::ofstream o(tmp.path());
    o << run::pose_csv_header() << "\n";
    for (const auto& p : poses) o << run::pose_csv_row(p) << "\n";
    if (!o.flush()) throw std::runtime_error("cannot write " + tmp.path());
  } else if (ext == ".json") {
    std::ofstream o(tmp.path());
    o << "[";
    for (std::size_t i = 0; i < poses.size(); ++i) {
      const auto& p = poses[i];
      o << (i ? ",\n " : "\n ") << "{\"t_us\": " << p.t_us << ", \"joints_mm\": [";
      for (int j = 0; j < 13; ++j)
        o << (j ? ", " : "") << "[" << p.joints_mm[j][0] << ", " << p.joints_mm[j][1] << ", " << p.joints_mm[j][2] << "]";
      o << "], \"confidence\": " << p.confidence << ", \"mask_ran\": " << (p.mask_ran ? 1 : 0)
        << ", \"stale\": " << (p.stale ? "true" : "false") << "}";
    }
    o << "\n]\n";
    if (!o.flush()) throw std::runtime_error("cannot write " + tmp.path());
  } else if (ext == ".h5") {
    namespace h5 = camera::h5;
    h5::H5Id f = h5::create_file(tmp.path());
    auto put = [&](const char* name, hid_t file_type, hid_t mem_type, std::vector<hsize_t> dims, const void* data) {
      h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), name);
      h5::H5Id props = h5::untimed_dataset_props();
      h5::H5Id ds = h5::check(H5Dcreate2(f.get(), name, file_type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), name);
      if (!poses.empty()) h5::check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
    };
    std::vector<std::int64_t> t;
    std::vector<float> j, c;
    std::vector<std::uint8_t> m;
    for (const auto& p : poses) {
      t.push_back(p.t_us);
      for (const auto& q : p.joints_mm) j.insert(j.end(), q.begin(), q.end());
      c.push_back(p.confidence);
      m.push_back(p.mask_ran);
    }
    const hsize_t n = poses.size();
    put("t_us", H5T_STD_I64LE, H5T_NATIVE_INT64, {n}, t.data());
    put("joints_mm", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n, 13, 3}, j.data());
    put("confidence", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n}, c.data());
    put("mask_ran", H5T_STD_U8LE, H5T_NATIVE_UINT8, {n}, m.data());
    f.reset();
  } else {
    throw UsageError("--out " + path + ": expected .csv, .json or .h5");
  }
  tmp.commit();
}

}  // namespace

int cmd_run(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  const Args a("run", argv, {"--weights", "--rate", "--out", "--beta", "--height-mm", "--depth-mm", "--threads", "--stats-json", "--viz",
                "--viz-every"},
               {"--camera", "--no-early-exit", "--keep-empty"});
  a.expect_positionals(0, 1);
  const auto w = a.value("--weights");
  if (!w) throw UsageError("run needs --weights W and an event FILE (or --camera)");
  if (a.flag("--camera")) throw UsageError("run --camera (live) is not built yet: record with `yelan record` and run on the file");
  if (a.positionals().empty()) throw UsageError("run needs an event FILE");
  const std::string in = a.positionals()[0];
  if (const auto o = a.value("--out")) {
    const std::string ext = std::filesystem::path(*o).extension().string();
    if (ext != ".csv" && ext != ".json" && ext != ".h5") throw UsageError("--out " + *o + ": expected .csv, .json or .h5");
  }
  if (const auto t = a.value("--threads")) {
    const auto n = parse_thread_count(*t);
    if (!n) throw UsageError("--threads '" + *t + "': expected 1..1024");
    set_threads(*n);
  }
  run::RunOptions opt;
  opt.rate_hz = std::stod(a.value_or("--rate", "50"));
  opt.beta = a.flag("--no-early-exit") ? 2.0 : std::stod(a.value_or("--beta", "0.99"));
  opt.body_height_mm = std::stod(a.value_or("--height-mm", "1700"));
  opt.fixed_depth_mm = std::stod(a.value_or("--depth-mm", "0"));
  opt.skip_empty = !a.flag("--keep-empty");

  auto reader = camera::open_event_file(in);
  const auto& info = reader->info();
  run::PosePipeline pipe(*w, info.width, info.height, opt);
  std::vector<run::Pose> poses;
  std::optional<run::RunViz> viz;
  if (const auto v = a.value("--viz")) viz.emplace(*v, info.width, info.height, a.int_value_or("--viz-every", 1, 1, 1 << 20));
  auto sink = [&](const run::Pose& p) {
    poses.push_back(p);
    if (viz) viz->add(p, pipe);
  };
  std::vector<camera::Event> ev;
  std::int64_t last_t = 0;
  std::string stopped;
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    try {
      if (reader->read(ev, 1 << 15) == 0) break;
    } catch (const std::exception& e) {
      stopped = e.what();  // a file ending mid-packet: keep every pose computed so far
    }
    if (!ev.empty()) {
      last_t = ev.back().t;
      pipe.push(ev, sink);
      ev.clear();
    }
    if (!stopped.empty()) break;
  }
  pipe.finish(last_t, sink);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (const auto o = a.value("--out")) write_poses(*o, poses);
  if (viz) err << viz->finish() << " pictures in " << *a.value("--viz") << "\n";
  const run::RunStats& s = pipe.stats();
  const double frac = s.ticks ? double(s.mask_runs) / double(s.ticks - s.stale + 1e-9) : 0;
  out << in << ": " << s.events << " events, " << s.poses << " poses at " << opt.rate_hz << " per second ("
      << (pipe.causal() ? "causal" : "windowed bidirectional") << ", config " << pipe.config_name() << "), " << std::fixed
      << std::setprecision(1) << double(s.poses) / wall << " poses/s on this machine; stage 1 ran on "
      << std::setprecision(1) << 100 * frac << "% of the ticks with events (beta " << std::setprecision(3) << opt.beta << "), " << s.stale
      << " ticks without events repeated the last pose\n"
      << std::setprecision(2) << "per tick ms p50/p99: TORE " << run::percentile(s.times.tore_ms, 0.5) << "/"
      << run::percentile(s.times.tore_ms, 0.99) << ", stage 1 " << run::percentile(s.times.stage1_ms, 0.5) << "/"
      << run::percentile(s.times.stage1_ms, 0.99) << ", stage 2 " << run::percentile(s.times.stage2_ms, 0.5) << "/"
      << run::percentile(s.times.stage2_ms, 0.99) << ", whole tick " << run::percentile(s.times.tick_ms, 0.5) << "/"
      << run::percentile(s.times.tick_ms, 0.99) << "\n";
  if (const auto j = a.value("--stats-json")) {
    std::ofstream f(*j);
    f << "{\"poses_per_s\": " << double(s.poses) / wall << ", \"p50_ms\": " << run::percentile(s.times.tick_ms, 0.5)
      << ", \"p99_ms\": " << run::percentile(s.times.tick_ms, 0.99) << ", \"mask_run_fraction\": " << frac
      << ", \"threads\": " << yelan::threads() << ", \"config\": \"" << pipe.config_name() << "\", \"poses\": " << s.poses
      << ", \"ticks\": " << s.ticks << ", \"stale_ticks\": " << s.stale << "}\n";
  }
  if (!stopped.empty()) {
    err << "yelan: error: " << stopped << " (the " << poses.size() << " poses computed before are written)\n";
    return 2;
  }
  return kOk;
}

}  // namespace yelan::cli
