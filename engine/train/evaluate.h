// Evaluation (SPEC section 7) on simulated test scenes: both networks as deployed (BN
// folded, the mask net's current mask binarised at 0.1 multiplying the TORE), joints
// denormalised with the true head depth (the paper protocol); MPJPE, PCK@150 and AUC, also
// root-aligned, per joint and per condition, and the mask IoU of stage 1.
#pragma once
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "camera/sim/simulator.h"
#include "engine/train/floors.h"
#include "engine/train/metrics.h"
#include "engine/train/pose_norm.h"

namespace yelan::train {

struct EvalSpec {
  std::string weights;
  std::vector<camera::sim::SimSpec> scenes;
  std::vector<std::string> recordings;  // *.yelan.h5 files, evaluated after the scenes
  std::uint64_t seed = 1;
  double seconds_per_scene = 1.0;
  bool true_mask = false;  // multiply by the simulator's mask instead of the mask net's
  bool frame_zoom = false;  // every window zoomed onto its dancer from the true joints (trainer's --frame-zoom)
  // A window's TORE holds the events of up to this long before it (5 s: all TORE reads, as in
  // `yelan run`); simulated scenes start anywhere in their clip and run this long first.
  double history_s = 5;
  bool floors = true;      // score the trivial predictors (floors.h) on the same frames
  // Simulated scenes frame the dancer (place_in_clip); false: the clip's own placement, as
  // every figure before this option was measured (dancers often partly out of the picture).
  bool framed = true;
  // Non-empty: a folder for one PNG per scene or recording (its name), the last frame of its
  // middle window, stage 1's mask against the truth (mask_picture.h); none
  // where stage 1 does not run (true_mask, or a config whose stage 2 reads no mask).
  std::string mask_pictures;
  std::optional<int> mask_grow;  // instead of the model's run.mask_grow
  bool keep_poses = false;       // fill EvalResult::poses (eval --poses)
};

// One scored frame (eval --poses): what a lifter or a refiner over the net's output trains on.
struct FramePose {
  std::string source;  // the scene's or recording's name
  std::string view;    // its view, "" where unknown
  int window = 0, frame = 0;  // the window's index in its scene, the frame's in the window
  std::int64_t t_us = 0;
  double z_ref = 0;    // the true head depth the prediction was denormalised with
  Intrinsics k{};
  Pose13 pred{}, truth{};
  std::array<std::uint8_t, kJoints> valid{};
};

struct EvalResult {
  PoseScores all;
  double mask_iou = 0;  // -1 where no stage 1 ran (true masks, or a config without one): n/a
  // condition name -> value -> scores (lighting, background, view, character, clothing, occlusion)
  std::map<std::string, std::map<std::string, PoseScores>> by_condition;
  // the same conditions' mask IoU (stage 1 against the true mask); empty with true masks
  std::map<std::string, std::map<std::string, double>> mask_iou_by_condition;
  // The same off the true silhouette's edge (engine/train/mask_overlap.h): what is left when a
  // cell either way at the outline is forgiven.
  double mask_iou_off_edge = 0;
  std::map<std::string, std::map<std::string, double>> mask_iou_off_edge_by_condition;
  // The same at the sensor's pixels (each with its cell's verdict): free of where the centre
  // sample falls in a cell.
  double mask_iou_px = 0;
  std::map<std::string, std::map<std::string, double>> mask_iou_px_by_condition;
  std::string config;
  std::uint64_t scenes = 0;
  std::map<std::string, PoseScores> floors;         // predictor name -> scores, same frames
  std::map<std::string, double> swap_share_by_view;  // share of frames better with L/R swapped
  // The same frames with each pose or its left/right swap, whichever is closer (an oracle):
  // how much of the error is telling left from right (front from back).
  PoseScores swap_oracle;
  // Image-plane and depth error of the model and, with floors, of the per-view floor.
  ErrorSplitScores split;
  std::optional<ErrorSplitScores> split_per_view_floor;
  int mask_pictures = 0;  // PNGs written to EvalSpec::mask_pictures
  std::vector<FramePose> poses;  // with EvalSpec::keep_poses, every scored frame in order
};

EvalResult evaluate(const EvalSpec& spec, std::ostream& err);

// `count` test-split presets drawn with `seed`, conditions (view x light x background)
// taking turns so every one is covered evenly.
std::vector<std::string> draw_test_scenes(std::uint64_t seed, int count);

// Scene i of an evaluation starts anywhere in its clip (a seeded offset; procedural dances
// have no clip end and start at 0); framed: the dancer turned to the view and centred in
// the picture over the scene (SimSpec::frame_dancer), as a dance game's player stands.
void place_in_clip(camera::sim::SimSpec& s, std::uint64_t seed, std::size_t i, bool framed = true);

// {"mpjpe_mm", "pck150", "auc", "mpjpe_root_mm", "pck150_root", "auc_root", "frames"} as JSON text.
std::string pose_scores_json(const PoseScores& s);

std::string eval_json(const EvalResult& r);
std::string eval_table(const EvalResult& r);
// The CSV of `eval --poses` (without --run): one row per frame, the camera's intrinsics, the
// prediction (mm, camera frame, under the true head depth), the label, and the sensor's size
// last (after validJ, so readers of the first 101 columns keep their indices).
std::string frame_poses_csv(const std::vector<FramePose>& poses);

}  // namespace yelan::train
