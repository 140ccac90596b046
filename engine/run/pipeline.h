// Streaming pose estimation (the product): events in, 13 joints in mm out, at any tick rate.
// Per event the TORE volume is updated; at each tick it is read out and downscaled; stage 1
// (the U-Net) runs only when the stored future mask for this tick has a score below beta
// (the paper's early exit); the masked TORE goes through stage 2, causal (the ConvLSTM state
// carried tick to tick, one tick of latency) or windowed bidirectional (a window of S ticks
// of latency), as the model's config says; joints are denormalised with a depth estimate
// (a body-height prior: the skeleton scales linearly with the head depth) or a given one.
// A tick with no new events repeats the last pose, flagged, and skips both stages.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "camera/event.h"
#include "layers/param.h"

namespace yelan::run {

struct RunOptions {
  double rate_hz = 50;        // poses per second
  double beta = -1;           // early-exit threshold on the mask scores; > 1 runs stage 1 every
                              // tick; < 0: the model's (its config's run.beta, else 0.99)
  double presence_threshold = 0.5;  // P(person) at or above which a tick has a person
  double body_height_mm = 1700;  // the depth prior
  double fixed_depth_mm = 0;  // > 0: use this head depth instead of the prior
  bool skip_empty = true;     // no events since the last tick: repeat the last pose
  int crop_margin = -1;       // stage 2's head on the mask's box grown by this many input
                              // pixels (0: whole frame; -1: the model's pose.crop_margin)
  int mask_crop_margin = -1;  // stage 1 on its last masks' box grown by this many input pixels
                              // while a dancer is there (0: whole frame; -1: the model's mask.crop_margin)
  // Ticks at origin + k / rate (e.g. 0: on a recording's mask and label times) instead of
  // one period after the first event.
  std::optional<std::int64_t> tick_origin_us;
  // P(person)'s {a, b} instead of the model's run.presence (calibrate refits under its fit:
  // the look-again rule reads the calibration, so the ticks depend on it).
  std::optional<std::array<double, 2>> presence_ab;
  // Stage 1's sigmoid cut instead of the model's run.mask_cut (calibrate's sweep of cuts).
  std::optional<double> mask_cut;
  // Stage 2's masks grown by this many input pixels instead of the model's run.mask_grow.
  std::optional<int> mask_grow;
  // P(person)'s smoothing time constant (s) instead of the model's run.presence.tau_s.
  std::optional<double> presence_tau_s;
  // The head depth's smoothing time constant (s) instead of the model's run.depth_tau_s.
  std::optional<double> depth_tau_s;
  // The skeleton's smoothing time constant (s) instead of the model's run.pose_tau_s.
  std::optional<double> pose_tau_s;
  // Whether the depth prior counts the forearms, instead of the model's run.depth_forearms.
  std::optional<bool> depth_forearms;
  // Stage 1 in bf16 on AMX where the CPU has it, or fp32, instead of the model's run.bf16.
  std::optional<bool> bf16;
  // Stage 2 in bf16 on AMX where the CPU has it, or fp32, instead of the model's run.pose_bf16.
  std::optional<bool> pose_bf16;
  // run.mask_max_age instead of the model's (0: none).
  std::optional<int> mask_max_age;
  // Seconds between stage 1's runs while it sees nobody, instead of the model's run.idle_recheck_s.
  std::optional<double> idle_recheck_s;
  // run.mask_mirror's margin d instead of the model's: stage 1 run again mirrored where its
  // current mask gives P(person) in [d, 1 - d] (0: never; a model with run.mask_mirror true
  // mirrors every run regardless).
  std::optional<double> mask_mirror_doubt;
  // On ticks where stage 2 alone reads the TORE behind a stored mask, read it out only in the
  // mask's box (the poses are the same; false: the whole sensor every tick, for comparison).
  bool tore_box = true;
  // Fill Pose::mask_mean_p and mask_blob (what calibrate's --ticks records; a flood fill and
  // a sigmoid per pixel of every mask stage 1 makes). Off, they stay 0.
  bool stage1_cues = false;
  // Binarise every future mask stage 1 makes, not only those up to run.mask_max_age that early
  // exit can reuse (bench early-exit scores each one's confidence against its true quality).
  bool cut_every_mask = false;
};

// A tick's pose. Presence comes from stage 1: the share of the frame the mask in use covers,
// its logarithm smoothed over the last ticks (PresenceSmoother), through the model's
// calibration (ModelConfig run.presence) to a probability. A model
// without stage 1 (mask.role none) has no opinion: presence 1 on every tick.
struct Pose {
  std::int64_t t_us = 0;
  std::array<std::array<float, 3>, 13> joints_mm{};  // camera frame; NaN when !person
  float confidence = 1;       // P(a person is there), calibrated
  bool person = true;         // confidence >= RunOptions::presence_threshold
  float mask_share = 0;       // the mask's share of the frame (what confidence is computed from)
  // More of what stage 1 says (recorded for calibration studies, with RunOptions::stage1_cues;
  // P(person) reads the share):
  float mask_mean_p = 0;      // its mean probability over the mask's pixels (0 for an empty mask)
  float mask_blob = 0;        // the largest 8-connected blob's share of the mask (0 for an empty mask)
  float mask_score = 0;       // its score for the mask in use (predicted 1 - mean |mask error|)
  float pose_confidence = 0;  // mean over joints of the last stage's xy peak probability
  bool mask_ran = false, stale = false;
  // Which of stage 1's masks stage 2 read: 0 the current frame's (stage 1 ran on this tick,
  // or is held while nobody is there), k a future mask predicted k x 20 ms ahead (early exit).
  int mask_age = 0;
  double head_depth_mm = 0;
};

struct StageTimes {
  std::vector<double> tore_ms, stage1_ms, stage2_ms, tick_ms;
};

struct RunStats {
  std::uint64_t ticks = 0, mask_runs = 0, stale = 0, events = 0, poses = 0;
  std::uint64_t mirror_runs = 0;  // stage 1's runs redone on the mirrored input (run.mask_mirror's margin)
  std::uint64_t person_poses = 0;  // poses with a person
  std::uint64_t gap_ticks = 0;  // skipped over gaps of more than 2 s without events
  double crop_area = 0;         // sum over stage-2 runs of the head's share of the frame
  std::uint64_t crop_runs = 0;  // stage-2 runs with cropping on
  double mask_crop_area = 0;         // sum over stage 1's cropped runs of the crop's share of the frame
  std::uint64_t mask_crop_runs = 0;  // stage 1's runs on a crop (mask.crop_margin)
  double tore_box_area = 0;     // sum over those ticks of the box's share of the frame
  std::uint64_t tore_box_ticks = 0;  // ticks that read the TORE in stage 2's box alone
  std::vector<double> stage1_run_ms;  // stage 1's time on each tick that ran it
  StageTimes times;
};

// Early exit's saving, estimated: the ticks with events that reused a stored mask, each
// costed at stage 1's median time on the ticks that ran it (the median, because the first
// run is cold and short files have few runs); 0 when stage 1 never ran.
double early_exit_saved_ms(const RunStats& s);
// The mean share of the frame stage 2's head ran on (1 when cropping was off).
double crop_share(const RunStats& s);

class PosePipeline {
 public:
  PosePipeline(const std::string& weights, int sensor_width, int sensor_height, const RunOptions& opt);
  ~PosePipeline();
  // Events in time order. Every tick whose time has passed is processed; poses go to `out`.
  void push(std::span<const camera::Event> events, const std::function<void(const Pose&)>& out);
  // Processes the ticks up to and including t_us (the end of a file), then flushes a partial window.
  void finish(std::int64_t t_us, const std::function<void(const Pose&)>& out);
  const RunStats& stats() const;
  std::string config_name() const;
  std::array<double, 2> presence_ab() const;  // the calibration P(person) is read with: {a, b}
  double beta() const;  // the early-exit threshold in use
  bool stage1_bf16() const;  // stage 1 in bf16 (run.bf16 or --bf16, and the CPU has AMX or AVX512-BF16)
  std::string stage1_precision() const;  // "fp32", "bf16 on AMX" or "bf16 Winograd on AVX512-BF16"
  bool stage2_bf16() const;  // stage 2 in bf16 (run.pose_bf16 or --pose-bf16, and the CPU has AMX)
  int mask_max_age() const;  // the age cap in use (0: none): run.mask_max_age_bf16 where stage 1 runs bf16 on AMX, run.mask_max_age_bf16_winograd on AVX512-BF16
  bool causal() const;
  // The time of the latest tick. A windowed (bidirectional) stage 2 hands out a window's poses
  // after its last tick: inside the callback the masks above are that tick's, so a pose of an
  // earlier tick of the window (t_us before this) cannot be paired with the mask it ran with.
  std::int64_t latest_tick_us() const;
  // Inside the callback: whether the masks below are the ones pose p ran with (a fresh tick,
  // the latest one), what scoring a mask against the truth at p's time needs.
  bool masks_are_for(const Pose& p) const { return !p.stale && p.t_us == latest_tick_us(); }
  // For pictures, valid inside the pose callback: the TORE volume of the latest tick (2K x
  // H x W at the sensor's size), the mask stage 2 read (the model's input size; a reused
  // future mask at run.mask_cut_reused) and its downscale.
  const std::vector<float>& last_tore() const;
  const std::vector<float>& last_mask() const;
  // The same mask as stage 1 cut it, before run.mask_grow: what its IoU and the pictures read
  // (and, through its share of the frame, the "person" verdict).
  const std::vector<float>& last_stage1_mask() const;
  // Stage 1's latest run: its N masks (the current frame and N-1 future ones, 20 ms apart;
  // binarised, the model's input size) and their scores. Under an age cap K masks after K are
  // left empty unless RunOptions::cut_every_mask is set.
  const std::vector<std::vector<float>>& stored_masks() const;
  const std::vector<float>& stored_scores() const;
  // Stage 1's latest run before the cut: its masks' logits at the model's input size (channel
  // 0 the current frame; the net's own buffer, nothing copied on the hot path). Lets one pass
  // score every cut (weights calibrate).
  const layers::Act& stage1_logits() const;
  // Stage 2's input of the latest tick: the masked, downscaled TORE (one frame, blocked).
  const layers::Act& last_input() const;
  int mask_downscale() const;
  double focal_px() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Streams the events of an event file up to end_us through `pipe` (then its ticks through
// end_us), poses to `out`. Returns the seconds spent in the pipeline, reading not counted.
double run_file(PosePipeline& pipe, const std::string& path, std::int64_t end_us, const std::function<void(const Pose&)>& out);

// The depth prior: head depth at which the predicted skeleton's limb lengths (upper arms,
// forearms, thighs, shanks) sum to a body of the given height (Drillis-Contini fractions).
// forearms false leaves the forearms out: they end at the hands, the joints a net places
// worst, and their lengths wander the most from tick to tick.
double head_depth_from_height(const std::array<std::array<double, 3>, 13>& joints_at_unit_depth, double height_mm,
                              bool forearms = true);

// The q-quantile (0..1) of per-tick times, nearest rank; 0 for none.
double percentile(std::vector<double> v, double q);

// The largest 8-connected blob of nonzero pixels of a w x h mask, as a share of all of them
// (0 for an empty mask): a dancer is one blob, furniture lit by a sweeping lamp several.
float largest_blob_share(const std::vector<float>& mask, int w, int h);

// P(person) for a mask covering `share` of the frame, by the model's calibration.
double presence_probability(double share, double a, double b);
// What P(person) reads: ln(share + 0.001).
double presence_feature(double share);
// P(person) from the (smoothed) feature.
double presence_probability_of_feature(double x, double a, double b);

// The presence feature averaged over time, exponentially with time constant tau_s (0: the
// tick's own): a furniture blob that a sweeping lamp lights for a few ticks, or a dancer
// half hidden for a few, does not flip the verdict; the price is latency (a dancer who
// walks in is called after about tau_s). One tick to the next: x += (1 - exp(-dt / tau)) (x_t - x).
class PresenceSmoother {
 public:
  explicit PresenceSmoother(double tau_s = 0) : tau_us_(tau_s * 1e6) {}
  double update(double share, std::int64_t t_us);  // the smoothed feature at t_us
  // The next update starts afresh from its own share (the fit's recordings, whose first
  // scored tick comes after the pipeline's smoothing has forgotten how it started).
  void reset() { have_ = false; }
  // Starts afresh at t_us from nobody seen (the feature of an empty mask): after a stream
  // starts or resumes, the first ticks (a TORE of a few milliseconds, the masks a net is
  // least sure of) need about tau_s of evidence to say "person", as someone walking in does.
  void start_empty(std::int64_t t_us);

 private:
  double tau_us_;
  bool have_ = false;
  double x_ = 0;
  std::int64_t t_ = 0;
};

// The head depth averaged over time: ln(depth) exponentially with time constant tau_s (0:
// none). The prior reads each tick's limb lengths, which wander with the pose net's errors
// from tick to tick, while a dancer's distance changes slowly. It starts afresh on its
// first tick, when time goes backwards, and after reset() (nobody there: whoever comes next
// stands somewhere else).
class DepthSmoother {
 public:
  explicit DepthSmoother(double tau_s = 0) : tau_us_(tau_s * 1e6) {}
  // The smoothed depth at t_us; an estimate that is not a depth (<= 0, NaN) is passed
  // through and leaves the average alone.
  double update(double depth_mm, std::int64_t t_us);
  void reset() { have_ = false; }

 private:
  double tau_us_;
  bool have_ = false;
  double x_ = 0;
  std::int64_t t_ = 0;
};

// The skeleton averaged over time: each joint at unit head depth (before the depth scales
// it), exponentially with time constant tau_s (0: none). Stage 2's joints jitter from tick to
// tick by more than a dancer moves in tens of milliseconds (the net hedges between the
// places a limb could be); the price is lag (about tau_s behind a limb that moves). It
// starts afresh on its first tick, when time goes backwards, and after reset() (nobody
// there, or a gap in the stream).
class JointSmoother {
 public:
  using Skeleton = std::array<std::array<double, 3>, 13>;
  explicit JointSmoother(double tau_s = 0) : tau_us_(tau_s * 1e6) {}
  // The smoothed skeleton at t_us. A skeleton with a joint that is not finite is passed
  // through and leaves the average alone.
  Skeleton update(const Skeleton& joints, std::int64_t t_us);
  void reset() { have_ = false; }

 private:
  double tau_us_;
  bool have_ = false;
  Skeleton x_{};
  std::int64_t t_ = 0;
};

// CSV: t_us, then x,y,z (mm) of the 13 joints in SPEC order (empty when no person),
// confidence (P(person)), mask_ran, person (0/1), pose_confidence, mask_share.
std::string pose_csv_header();
std::string pose_csv_row(const Pose& p);

}  // namespace yelan::run
