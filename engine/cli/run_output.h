// One `yelan run`, from a file or live from a camera: the pose pipeline, where its poses go
// (CSV, JSON or HDF5, and --viz pictures) and the summary printed at the end.
#pragma once
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "camera/event.h"
#include "engine/run/pipeline.h"
#include "engine/run/viz.h"

namespace yelan::cli {

struct RunSetup {
  std::string weights;
  run::RunOptions options;
  std::optional<std::string> out;         // .csv, .json or .h5
  std::optional<std::string> stats_json;  // figures of the run
  std::optional<std::string> viz_dir;
  int viz_every = 1;
};

// Throws UsageError unless `path` ends in .csv, .json or .h5.
void check_pose_output(const std::string& path);

// Writes poses atomically (a temporary file renamed into place) as CSV, JSON or HDF5.
void write_poses(const std::string& path, const std::vector<run::Pose>& poses);

class RunSession {
 public:
  // `live`: a CSV output is written at `out` itself, one flushed row per pose as computed,
  // so that it can be followed while it grows and every row survives whatever ends the
  // run. Otherwise (and for JSON and HDF5 always) the poses are kept and written at the end.
  RunSession(const RunSetup& setup, int sensor_width, int sensor_height, bool live);

  void push(std::span<const camera::Event> events);  // poses go to the outputs
  void finish(std::int64_t t_us);                     // the last ticks and a partial window
  // Writes what is written at the end (JSON, HDF5, file-mode CSV, --viz video, --stats-json);
  // once, on every way out of a run. `wall_s` is the run's duration for the rates.
  void write_outputs(double wall_s, std::ostream& err);
  // The summary lines (events, poses, rates, stage 1 share, per-stage times).
  void report(const std::string& source, double wall_s, std::ostream& out) const;

  std::uint64_t poses() const { return poses_written_; }
  // Stage 1 runs over the ticks that had events, 0..1.
  double stage1_share() const;
  double saved_share() const;  // early exit's saving over the time the ticks would have taken
  const run::PosePipeline& pipeline() const { return pipe_; }
  const RunSetup& setup() const { return setup_; }

 private:
  void add(const run::Pose& p);
  void write_live_csv(const std::string& text);

  RunSetup setup_;
  bool live_;
  run::PosePipeline pipe_;
  std::optional<run::RunViz> viz_;
  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, FileCloser> live_csv_;  // a live run's CSV, grown in place
  std::vector<run::Pose> kept_;
  std::uint64_t poses_written_ = 0;
  bool outputs_written_ = false;
};

}  // namespace yelan::cli
