// Pictures of a run (`yelan run --viz DIR`): per pose a PNG of three panels: the TORE's
// newest ON/OFF slots (red/blue) with the mask in use tinted green, the same with the
// predicted skeleton projected, and a side view of the 3D skeleton (depth to the right,
// 1 px = 10 mm). ffmpeg, when installed, turns them into DIR/run.mp4.
#pragma once
#include <string>

#include "engine/run/pipeline.h"

namespace yelan::run {

class RunViz {
 public:
  RunViz(const std::string& dir, int sensor_width, int sensor_height, int every = 1);
  void add(const Pose& p, const PosePipeline& pipe);
  // Writes DIR/run.mp4 if ffmpeg is present; returns how many PNGs were written.
  int finish();

 private:
  std::string dir_;
  int w_, h_, every_, seen_ = 0, written_ = 0;
};

}  // namespace yelan::run
