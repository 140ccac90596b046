// The streaming pipeline (engine/run/pipeline.h) scored on simulated scenes: events from the
// simulator go through PosePipeline exactly as `yelan run` feeds them, and each pose is
// compared with the simulator's label at the pose's time. Two depths: the paper protocol
// (the prediction rescaled to the true head depth) and as deployed (the body-height prior).
// Also what the run cost: the share of ticks that ran stage 1 and the time per tick by stage.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "camera/sim/simulator.h"
#include "engine/run/pipeline.h"
#include "engine/run/presence.h"
#include "engine/train/metrics.h"

namespace yelan::run {

// Scenes simulated once (events in memory, the simulator kept for its labels), so a sweep
// runs the pipeline many times on identical events and times the pipeline alone.
struct SimulatedScene {
  std::unique_ptr<camera::sim::Simulator> sim;
  std::vector<camera::Event> events;
  double warmup_s = 0.1;           // poses before this (TORE without history) are not scored
  // At each mask tick (the simulator's mask_hz), whether any pixel of the dancer shows (the
  // true mask after occlusion is not empty): a dancer wholly behind furniture makes no events.
  std::vector<std::int64_t> mask_t;
  std::vector<std::uint8_t> dancer_shows;
  // Scenes with a dancer: the true mask at each mask tick, one bit a pixel (row-major, width
  // times height bits a tick, 11 kB on a DAVIS346), for the mask IoU as deployed.
  // Kept from the warm-up's end on: bit masks of ticks first_bits_tick, first_bits_tick + 1, ...
  std::vector<std::uint64_t> mask_bits;
  std::size_t first_bits_tick = 0;
  // Tick k's mask unpacked into out (width * height bytes, 1 = dancer); false where not kept.
  bool true_mask(std::size_t k, std::vector<std::uint8_t>& out) const;
};

// Scene i runs with a seed drawn from `seed` and i, for warmup_s + seconds.
std::vector<SimulatedScene> simulate_scenes(const std::vector<camera::sim::SimSpec>& scenes, std::uint64_t seed,
                                            double seconds, double warmup_s, std::ostream& progress);

// One pose of an evaluation with what it was scored against (`yelan eval --run --poses`).
struct ScoredPose {
  std::string source;  // the recording's or scene's name
  bool dancer = true;  // false: a recording with nobody in it (no label)
  Pose pose;
  std::array<std::array<double, 3>, 13> truth{};  // mm, camera frame
  std::array<std::uint8_t, 13> valid{};           // 0: the joint is not in the picture
};

// The CSV of `eval --run --poses`: one row per pose, its verdict, head depths, joints as run
// (empty when no person) and the label (empty without a dancer).
std::string scored_poses_csv(const std::vector<ScoredPose>& poses);

struct StreamEvalResult {
  train::PoseScores paper;         // head depth from the label (the paper's protocol)
  train::PoseScores deployed;      // head depth from the pipeline's estimate
  std::uint64_t ticks = 0, mask_runs = 0, mirror_runs = 0, stale = 0, poses_scored = 0;
  // Poses in the scored span that said "no person" on a scene with a dancer in the picture
  // (no joints to score; a miss of the presence verdict) and those that said "person".
  std::uint64_t person_missed = 0, person_found = 0;
  // Of those, the poses whose dancer was wholly hidden (joints in the picture, not one pixel of
  // the dancer visible at the latest mask tick: nothing for an event camera to see) and those
  // of them that said "person". The visible dancer's hit rate leaves them out.
  std::uint64_t dancer_hidden = 0, dancer_hidden_called = 0;
  // The poses where any pixel of the dancer shows, and of them those that said "person".
  std::uint64_t dancer_shown() const { return person_found + person_missed - dancer_hidden; }
  std::uint64_t dancer_shown_called() const { return person_found - dancer_hidden_called; }
  double mask_run_fraction = 0;    // of the ticks that ran stage 2
  bool stage1_bf16 = false;        // stage 1 ran in bf16 (PosePipeline::stage1_bf16)
  std::string stage1_precision = "fp32";  // PosePipeline::stage1_precision
  bool stage2_bf16 = false;        // PosePipeline::stage2_bf16
  int mask_max_age = 0;            // the age cap it ran under (0: none)
  double mirror_run_fraction = 0;  // of the same ticks, stage 1 run again mirrored (run.mask_mirror)
  double ms_per_tick = 0;          // mean over ticks, all stages
  double tore_ms = 0, stage1_ms = 0, stage2_ms = 0;  // mean per tick (stage 1: over every tick)
  double wall_s = 0;               // pipeline time alone
  double crop_share = 1;           // mean share of the frame stage 2's head ran on
  std::uint64_t mask_crop_runs = 0;  // stage 1's runs on a crop (mask.crop_margin)
  double mask_crop_share = 1;        // their mean share of the frame
  // The deployed head depth against the true one, over the scored poses (0 when none).
  double depth_ratio_median = 0, depth_abs_error_mm = 0;
  // Recordings and simulated scenes without a dancer (`-empty`): their poses and those that said person.
  std::uint64_t empty_poses = 0, empty_called_person = 0;
  // Every pose's verdict under the conditions its recording's or scene's name says: dancer
  // recordings and scenes count all their poses in the span, the dancer in the picture or not.
  std::map<std::string, PresenceReport::Condition> presence_by_condition;
  std::vector<ScoredPose> poses;  // every pose in the scored spans, when asked for (keep_poses)
  // At every scored tick of a dancer recording or scene, the mask stage 1 left for stage 2
  // (this tick's, or a future mask early exit reused; cut, before run.mask_grow) against the
  // true mask at the net's size, pooled; -1 where not measured (no dancer, or no mask net). A
  // windowed (bidirectional) stage 2 scores the last tick of each window only.
  double mask_iou = -1;
  std::uint64_t mask_ticks = 0;
  std::map<std::string, double> mask_iou_by_condition;  // the condition words of the recordings' names
  // The same at the sensor's pixels, each with its cell's verdict (train::MaskOverlap::iou_px).
  double mask_iou_px = -1;
  std::map<std::string, double> mask_iou_px_by_condition;
  // The same by the age of the mask in use (Pose::mask_age: 0 this tick's, k a future mask
  // reused k ticks after stage 1 ran): where early exit loses the masks. Pooled per age.
  struct AgeIou {
    double iou = 0;
    std::uint64_t ticks = 0;
  };
  std::map<int, AgeIou> mask_iou_by_age;
};

StreamEvalResult evaluate_stream(const std::string& weights, const std::vector<SimulatedScene>& scenes,
                                 const RunOptions& run, bool keep_poses = false);

// The same on labelled recordings on disk (*.yelan.h5, dancer and empty scenes): each run
// through the pipeline from its first event, ticks on the recording's label clock, the
// poses from skip_s to `seconds` scored (on empty scenes: counted, and those saying person).
StreamEvalResult evaluate_recordings(const std::string& weights, const std::vector<std::string>& recordings, double seconds,
                                     double skip_s, const RunOptions& run, std::ostream& progress,
                                     bool keep_poses = false);

}  // namespace yelan::run
