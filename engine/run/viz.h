// Pictures of a run (`yelan run --viz DIR`): per pose a PNG of three panels: the TORE's
// newest ON/OFF slots (red/blue) with the mask in use tinted green, the same with the
// predicted skeleton projected, and a side view of the 3D skeleton (depth to the right,
// 1 px = 10 mm). ffmpeg, when installed, turns them into DIR/run.mp4. A target ending in
// .mp4 is a video: the frames go to TARGET.frames/, ffmpeg (required) encodes them at the
// pose rate into a temporary file renamed to TARGET, and the frames are removed.
#pragma once
#include <string>

#include "engine/run/pipeline.h"

namespace yelan::run {

class RunViz {
 public:
  // fps: the frames' rate in the video (the pose rate over `every`).
  RunViz(const std::string& target, int sensor_width, int sensor_height, int every = 1, double fps = 25);
  void add(const Pose& p, const PosePipeline& pipe);
  // Makes the video (see above).
  void finish();
  // After finish(), what a user should open: the video, or the folder of PNGs when no video
  // was asked for or ffmpeg failed (the frames are kept).
  std::string summary() const;

  static bool have_ffmpeg();
  // Throws std::invalid_argument when the target cannot be made: a video without ffmpeg.
  static void check_target(const std::string& target);

 private:
  std::string dir_, video_;
  int w_, h_, every_, seen_ = 0, written_ = 0;
  bool encoded_ = false;  // the video (or DIR/run.mp4) was made
  std::string problem_;   // why it was not, when ffmpeg was run
  double fps_;
};

}  // namespace yelan::run
