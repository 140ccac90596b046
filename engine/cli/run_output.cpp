#include "engine/cli/run_output.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "engine/cli/args.h"
#include "engine/threads.h"

namespace yelan::cli {
namespace {

std::string extension(const std::string& path) { return std::filesystem::path(path).extension().string(); }

}  // namespace

void check_pose_output(const std::string& path) {
  const std::string ext = extension(path);
  if (ext != ".csv" && ext != ".json" && ext != ".h5") throw UsageError("--out " + path + ": expected .csv, .json or .h5");
}

void write_poses(const std::string& path, const std::vector<run::Pose>& poses) {
  check_pose_output(path);
  const std::string ext = extension(path);
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
      o << (i ? ",\n " : "\n ") << "{\"t_us\": " << p.t_us << ", \"joints_mm\": ";
      if (p.person) {
        o << "[";
        for (int j = 0; j < 13; ++j)
          o << (j ? ", " : "") << "[" << p.joints_mm[j][0] << ", " << p.joints_mm[j][1] << ", " << p.joints_mm[j][2] << "]";
        o << "]";
      } else {
        o << "null";  // no person: no joints
      }
      o << ", \"confidence\": " << p.confidence << ", \"person\": " << (p.person ? "true" : "false")
        << ", \"pose_confidence\": " << p.pose_confidence << ", \"mask_share\": " << p.mask_share
        << ", \"mask_ran\": " << (p.mask_ran ? 1 : 0) << ", \"mask_age\": " << p.mask_age
        << ", \"stale\": " << (p.stale ? "true" : "false") << "}";
    }
    o << "\n]\n";
    if (!o.flush()) throw std::runtime_error("cannot write " + tmp.path());
  } else {
    namespace h5 = camera::h5;
    h5::H5Id f = h5::create_file(tmp.path());
    auto put = [&](const char* name, hid_t file_type, hid_t mem_type, std::vector<hsize_t> dims, const void* data) {
      h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), name);
      h5::H5Id props = h5::untimed_dataset_props();
      h5::H5Id ds = h5::check(H5Dcreate2(f.get(), name, file_type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), name);
      if (!poses.empty()) h5::check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
    };
    std::vector<std::int64_t> t;
    std::vector<float> j, c, pc, share;
    std::vector<std::uint8_t> m, person;
    std::vector<std::int32_t> age;
    for (const auto& p : poses) {
      t.push_back(p.t_us);
      for (const auto& q : p.joints_mm) j.insert(j.end(), q.begin(), q.end());
      c.push_back(p.confidence);
      m.push_back(p.mask_ran);
      person.push_back(p.person);
      pc.push_back(p.pose_confidence);
      share.push_back(p.mask_share);
      age.push_back(p.mask_age);
    }
    const hsize_t n = poses.size();
    put("t_us", H5T_STD_I64LE, H5T_NATIVE_INT64, {n}, t.data());
    put("joints_mm", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n, 13, 3}, j.data());
    put("confidence", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n}, c.data());
    put("mask_ran", H5T_STD_U8LE, H5T_NATIVE_UINT8, {n}, m.data());
    put("person", H5T_STD_U8LE, H5T_NATIVE_UINT8, {n}, person.data());  // joints_mm NaN where 0
    put("pose_confidence", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n}, pc.data());
    put("mask_share", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {n}, share.data());
    put("mask_age", H5T_STD_I32LE, H5T_NATIVE_INT32, {n}, age.data());
    f.reset();
  }
  tmp.commit();
}

RunSession::RunSession(const RunSetup& setup, int sensor_width, int sensor_height, bool live)
    : setup_(setup), live_(live), pipe_(setup.weights, sensor_width, sensor_height, setup.options) {
  if (setup_.viz_dir)
    viz_.emplace(*setup_.viz_dir, sensor_width, sensor_height, setup_.viz_every, setup_.options.rate_hz);
  if (live_ && setup_.out && extension(*setup_.out) == ".csv") {
    // Grown in place so that it can be followed while the camera runs, so no temp file and
    // rename: O_NOFOLLOW keeps a link planted at OUT from being written through.
    const int fd = ::open(setup_.out->c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0 && errno == ELOOP)
      throw UsageError("--out " + *setup_.out + " is a symbolic link: refusing to write through it");
    if (fd < 0) throw std::runtime_error("cannot write " + *setup_.out + ": " + std::strerror(errno));
    live_csv_.reset(::fdopen(fd, "w"));
    if (!live_csv_) {
      ::close(fd);
      throw std::runtime_error("cannot write " + *setup_.out);
    }
    write_live_csv(run::pose_csv_header() + "\n");
  }
}

void RunSession::write_live_csv(const std::string& text) {
  if (std::fputs(text.c_str(), live_csv_.get()) < 0 || std::fflush(live_csv_.get()) != 0)
    throw std::runtime_error("cannot write " + *setup_.out + " (disk full?)");
}

void RunSession::add(const run::Pose& p) {
  ++poses_written_;
  if (live_csv_) {
    write_live_csv(run::pose_csv_row(p) + "\n");
  } else if (setup_.out) {
    kept_.push_back(p);
  }
  if (viz_) viz_->add(p, pipe_);
}

void RunSession::push(std::span<const camera::Event> events) {
  pipe_.push(events, [this](const run::Pose& p) { add(p); });
}

void RunSession::finish(std::int64_t t_us) {
  pipe_.finish(t_us, [this](const run::Pose& p) { add(p); });
}

double RunSession::stage1_share() const {
  const run::RunStats& s = pipe_.stats();
  return s.ticks ? double(s.mask_runs) / double(s.ticks - s.stale + 1e-9) : 0;
}

double RunSession::saved_share() const {
  const run::RunStats& s = pipe_.stats();
  double spent = 0;
  for (double ms : s.times.tick_ms) spent += ms;
  const double saved = run::early_exit_saved_ms(s);
  return spent + saved > 0 ? saved / (spent + saved) : 0;
}

void RunSession::write_outputs(double wall_s, std::ostream& err) {
  if (outputs_written_) return;
  outputs_written_ = true;
  if (live_csv_) {
    if (std::fclose(live_csv_.release()) != 0) throw std::runtime_error("cannot write " + *setup_.out);
  } else if (setup_.out) {
    write_poses(*setup_.out, kept_);
  }
  if (viz_) {
    viz_->finish();
    err << viz_->summary() << "\n";
  }
  if (setup_.stats_json) {
    const run::RunStats& s = pipe_.stats();
    camera::TempFile tmp(*setup_.stats_json);
    std::ofstream f(tmp.path());
    f << "{\"poses_per_s\": " << double(s.poses) / wall_s << ", \"p50_ms\": " << run::percentile(s.times.tick_ms, 0.5)
      << ", \"p99_ms\": " << run::percentile(s.times.tick_ms, 0.99) << ", \"mask_run_fraction\": " << stage1_share()
      << ", \"threads\": " << yelan::threads() << ", \"config\": \"" << pipe_.config_name() << "\", \"poses\": " << s.poses
      << ", \"ticks\": " << s.ticks << ", \"stale_ticks\": " << s.stale
      << ", \"person_share\": " << (s.poses ? double(s.person_poses) / double(s.poses) : 0.0)
      << ", \"crop_share\": " << run::crop_share(s)
      << ", \"early_exit_saved_ms\": " << run::early_exit_saved_ms(s) << ", \"early_exit_saved_share\": " << saved_share()
      << "}\n";
    if (!f.flush()) throw std::runtime_error("cannot write " + tmp.path());
    f.close();
    tmp.commit();
  }
}

void RunSession::report(const std::string& source, double wall_s, std::ostream& out) const {
  const run::RunStats& s = pipe_.stats();
  const run::StageTimes& t = s.times;
  const auto p50_p99 = [](const std::vector<double>& v) {
    std::ostringstream o;
    o << std::fixed << std::setprecision(2) << run::percentile(v, 0.5) << "/" << run::percentile(v, 0.99);
    return o.str();
  };
  out << source << ": " << s.events << " events, " << s.poses << " poses at " << setup_.options.rate_hz
      << " per second (" << (pipe_.causal() ? "causal" : "windowed bidirectional") << ", config " << pipe_.config_name()
      << "), " << std::fixed << std::setprecision(1) << double(s.poses) / wall_s
      << " poses/s on this machine; stage 1 ran on " << 100 * stage1_share() << "% of the ticks with events (beta "
      << std::defaultfloat << std::setprecision(3) << pipe_.beta() << std::fixed << std::setprecision(1) << "), " << s.stale
      << " ticks without events repeated the last pose; a person on " << (s.poses ? 100.0 * double(s.person_poses) / double(s.poses) : 0.0) << "% of the poses\n"
      << "per tick ms p50/p99: TORE " << p50_p99(t.tore_ms) << ", stage 1 " << p50_p99(t.stage1_ms) << ", stage 2 "
      << p50_p99(t.stage2_ms) << ", whole tick " << p50_p99(t.tick_ms) << "\n";
  if (s.mirror_runs)
    out << "stage 1 ran again on the mirrored input on " << s.mirror_runs << " of its " << s.mask_runs
        << " runs (run.mask_mirror: where the plain run left presence in doubt)\n";
  if (s.mask_runs)
    out << "early exit saved about " << std::setprecision(1) << run::early_exit_saved_ms(s) << " ms of stage 1 ("
        << 100 * saved_share() << "% of what the ticks would have taken with stage 1 on each)\n";
  if (s.mask_crop_runs)
    out << "stage 1 ran on " << std::setprecision(1) << 100 * s.mask_crop_area / double(s.mask_crop_runs)
        << "% of the frame on " << s.mask_crop_runs << " of its " << s.mask_runs << " runs (cropped to its last masks' box)\n";
  if (s.crop_runs)
    out << "stage 2's head ran on " << std::setprecision(1) << 100 * run::crop_share(s)
        << "% of the frame on average (cropped to the mask's box)\n";
  out.unsetf(std::ios::floatfield);
  out << std::setprecision(6);
}

}  // namespace yelan::cli
