// Training samples straight from the simulator, with no disk: windows of S consecutive
// frames at frame_hz, each frame the TORE volume read out at the frame time (the network's
// input), the human mask rendered at that time, and the 3D joints (camera frame, mm) with
// their validity. Scenes are drawn in turn from a list, each run with a fresh seed from the
// stream's seed, so the stream is endless and reproducible.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "camera/repr/tore.h"
#include "camera/sim/simulator.h"

namespace yelan::camera::sim {

struct SimFrame {
  std::int64_t t_us = 0;
  std::vector<float> tore;          // 2K x H x W, channel-major
  std::vector<float> counts;        // with WindowStreamOptions::counts: 2 x H x W, events of each
                                    // polarity (positive first) in the frame period ending here
  std::vector<std::uint8_t> mask;   // H x W, 1 = human
  Joints13 joints_mm;               // camera frame
  std::array<std::uint8_t, kJointCount> valid{};
};

struct SimWindow {
  std::string scene;                // the preset or spec name
  std::uint64_t seed = 0;
  CameraModel camera;
  std::vector<SimFrame> frames;     // S of them, 1/frame_hz apart
};

struct WindowStreamOptions {
  int window = 16;                  // frames per window (S)
  double frame_hz = 50;             // the training frame rate (20 ms)
  double warmup_s = 0.1;            // simulated before the first frame, so TORE has history
  double history_s = 0;             // recordings: a window's TORE holds the events of up to this
                                    // long before its first frame (5 s: all that TORE reads, as in
                                    // `yelan run`); windows still start warmup_s in. 0: warmup_s
  double scene_s = 2.0;             // each scene runs this long before the next one starts
  ToreOptions tore;
  bool shuffle = false;             // scene k is a seeded random pick of the list, not k mod n
  // Recordings, shuffled: `cursors` recordings are open at once and window k comes from
  // cursor k mod cursors (a batch's windows from different recordings); each visit to a
  // recording serves `windows_per_visit` windows at seeded times in increasing order, read
  // in one pass, so the 5 s of history is read once per visit, not once per window.
  int cursors = 1, windows_per_visit = 1;
  bool spread = false;              // recordings, shuffled, one cursor: window k from recording
                                    // k mod n (each in turn, so a small sample covers the split)
  bool counts = false;              // also fill SimFrame::counts (constant-time event frames)
  // Recordings without counts: only the first tore_frames frames of a window get a TORE
  // read-out (the rest carry masks and labels alone: the mask net's future-mask targets);
  // 0: every frame. The read-outs given are the same values either way.
  int tore_frames = 0;
};

class SimWindowStream {
 public:
  SimWindowStream(std::vector<SimSpec> scenes, std::uint64_t seed, WindowStreamOptions options = {});
  ~SimWindowStream();
  // Fills the next window. Windows of one scene follow each other without overlap.
  void next(SimWindow& out);
  std::uint64_t scenes_started() const { return started_; }
  // The next window comes from scene number k (each scene is seeded by its number alone,
  // so a resumed trainer gets exactly the data an uninterrupted one would have).
  void seek_scene(std::uint64_t k) {
    started_ = k;
    sim_.reset();
  }

 private:
  struct Sink;
  void start_scene();
  std::vector<SimSpec> scenes_;
  std::uint64_t seed_;
  WindowStreamOptions opt_;
  std::uint64_t started_ = 0;
  std::unique_ptr<Simulator> sim_;
  std::unique_ptr<Sink> sink_;
  std::int64_t frame_index_ = 0;  // next frame of the current scene
};

}  // namespace yelan::camera::sim
