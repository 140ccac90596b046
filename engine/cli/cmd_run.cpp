// `yelan run`: events from a file, or live from a camera (--camera), -> 3D poses (engine/run),
// written as CSV, JSON or HDF5.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "camera/io/event_reader.h"
#include "engine/cli/args.h"
#include "engine/cli/camera_open.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/cli/run_live.h"
#include "engine/cli/run_output.h"
#include "engine/run/viz.h"
#include "engine/threads.h"

namespace yelan::cli {
namespace {

// `--camera` takes an optional serial, which Args cannot express: take `--camera`,
// `--camera=SERIAL` and `--camera SERIAL` out of argv first. The word after a bare
// --camera is a serial when it is no option and no existing path and has no '.' or '/'
// (serials are 8 ASCII characters; event files have extensions).
struct CameraChoice {
  bool wanted = false;
  std::optional<std::string> serial;
};

CameraChoice take_camera(std::vector<std::string>& argv) {
  CameraChoice c;
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--") {
      rest.insert(rest.end(), argv.begin() + static_cast<std::ptrdiff_t>(i), argv.end());
      break;
    }
    const bool bare = a == "--camera", inline_serial = a.rfind("--camera=", 0) == 0;
    if (!bare && !inline_serial) {
      rest.push_back(a);
      continue;
    }
    if (c.wanted) throw UsageError("option --camera given twice");
    c.wanted = true;
    if (inline_serial) {
      c.serial = a.substr(9);
      if (c.serial->empty()) throw UsageError("--camera=: expected a serial number");
    } else if (i + 1 < argv.size()) {
      const std::string& next = argv[i + 1];
      std::error_code ec;
      if (!next.empty() && next[0] != '-' && next.find_first_of("./") == std::string::npos &&
          !std::filesystem::exists(next, ec))
        c.serial = argv[++i];
    }
  }
  argv = std::move(rest);
  return c;
}

}  // namespace

int cmd_run(const std::vector<std::string>& argv_in, std::ostream& out, std::ostream& err) {
  std::vector<std::string> argv = argv_in;
  const CameraChoice cam = take_camera(argv);
  const Args a("run", argv, {"--weights", "--rate", "--out", "--beta", "--height-mm", "--depth-mm", "--depth-tau", "--pose-tau", "--idle-recheck", "--threads",
                             "--mask-mirror", "--mask-max-age", "--stats-json", "--viz", "--viz-every", "--duration", "--crop-margin",
                             "--mask-crop-margin", "--bf16", "--pose-bf16"},
               {"--no-early-exit", "--keep-empty"});
  a.expect_positionals(0, 1);
  const auto w = a.value("--weights");
  if (!w) throw UsageError("run needs --weights W and an event FILE (or --camera)");
  if (cam.wanted && !a.positionals().empty())
    throw UsageError("run reads either an event FILE or the camera (--camera [SERIAL]), not both (got '" +
                     a.positionals()[0] + "')");
  if (!cam.wanted && a.positionals().empty()) throw UsageError("run needs an event FILE (or --camera)");
  if (!cam.wanted && a.value("--duration")) throw UsageError("--duration is for --camera (a file runs to its end)");
  std::optional<std::chrono::milliseconds> duration;
  if (const auto d = a.value("--duration")) duration = std::chrono::milliseconds(std::llround(parse_duration_s(*d) * 1000));
  RunSetup setup;
  setup.weights = *w;
  setup.out = a.value("--out");
  std::vector<std::string> inputs = {*w};
  if (!a.positionals().empty()) inputs.push_back(a.positionals()[0]);
  if (setup.out) {
    check_pose_output(*setup.out);
    check_output("--out", *setup.out, inputs);
  }
  setup.stats_json = a.value("--stats-json");
  if (setup.stats_json) check_output("--stats-json", *setup.stats_json, inputs);
  setup.viz_dir = a.value("--viz");
  if (setup.viz_dir) {
    try {
      run::RunViz::check_target(*setup.viz_dir);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  }
  setup.viz_every = a.int_value_or("--viz-every", 1, 1, 1 << 20);
  if (const auto t = a.value("--threads")) {
    const auto n = parse_thread_count(*t);
    if (!n) throw UsageError("--threads '" + *t + "': expected 1..1024");
    set_threads(*n);
  }
  run::RunOptions& opt = setup.options;
  opt.rate_hz = a.number_or("--rate", 50, 0, 10000, true);
  opt.beta = a.flag("--no-early-exit") ? 2.0 : a.number_or("--beta", -1, 0, 1);  // -1: the model's
  opt.body_height_mm = a.number_or("--height-mm", 1700, 500, 2500);
  opt.fixed_depth_mm = a.number_or("--depth-mm", 0, 100, 100000);  // absent: the body-height prior
  if (a.value("--depth-tau")) opt.depth_tau_s = a.number_or("--depth-tau", 0, 0, 60);
  if (a.value("--pose-tau")) opt.pose_tau_s = a.number_or("--pose-tau", 0, 0, 10);
  if (a.value("--idle-recheck")) opt.idle_recheck_s = a.number_or("--idle-recheck", 0, 0, 1);
  if (a.value("--mask-max-age")) opt.mask_max_age = a.int_value_or("--mask-max-age", 0, 0, 1000);
  if (a.value("--bf16")) opt.bf16 = a.on_off("--bf16");
  if (a.value("--pose-bf16")) opt.pose_bf16 = a.on_off("--pose-bf16");
  if (a.value("--mask-mirror")) opt.mask_mirror_doubt = a.number_or("--mask-mirror", 0, 0, 0.499);
  opt.skip_empty = !a.flag("--keep-empty");
  if (a.value("--crop-margin")) opt.crop_margin = a.int_value_or("--crop-margin", 0, 0, 4096);
  if (a.value("--mask-crop-margin")) opt.mask_crop_margin = a.int_value_or("--mask-crop-margin", 0, 0, 4096);

  if (cam.wanted) {
    OpenCamera c = open_camera(cam.serial);
    LiveRun live{setup, describe_camera(c.info), &err == &std::cerr && ::isatty(STDERR_FILENO)};
    err << "running on " << live.camera_name << " (" << c.chip << ", " << c.device->width() << "x"
        << c.device->height() << ")" << (duration ? "" : "; Ctrl-C stops") << "\n";
    InterruptGuard guard;
    return run_live(*c.device, *c.transport, live, until_stopped(duration), out, err);
  }

  const std::string in = a.positionals()[0];
  auto reader = camera::open_event_file(in);
  RunSession session(setup, reader->info().width, reader->info().height, false);
  std::vector<camera::Event> ev;
  std::int64_t last_t = 0;
  std::string stopped;
  const auto start = std::chrono::steady_clock::now();
  InterruptGuard guard;  // Ctrl-C / SIGTERM: stop reading, write every pose computed so far
  for (;;) {
    if (InterruptGuard::interrupted()) {
      stopped = "interrupted";
      break;
    }
    try {
      if (reader->read(ev, 1 << 15) == 0) break;
    } catch (const std::exception& e) {
      stopped = e.what();  // a file ending mid-packet: keep every pose computed so far
    }
    if (!ev.empty()) {
      last_t = ev.back().t;
      session.push(ev);
      ev.clear();
    }
    if (!stopped.empty()) break;
  }
  session.finish(last_t);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  session.write_outputs(wall, err);
  session.report(in, wall, out);
  if (stopped == "interrupted") {
    err << "yelan: interrupted: the " << session.poses() << " poses computed so far are written\n";
    return kRuntimeError;
  }
  if (!stopped.empty()) {
    err << "yelan: error: " << printable(stopped) << " (the " << session.poses() << " poses computed before are written)\n";
    return kUsageError;
  }
  return kOk;
}

}  // namespace yelan::cli
