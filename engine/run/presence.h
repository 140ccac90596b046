// Calibrating presence: `yelan run`'s P(person) is a logistic function of ln(s + 0.001), s
// the share of the frame the mask in use covers. Its two numbers are fitted here on ticks of
// labelled recordings (scenes with a dancer and empty ones) run through the deployed
// pipeline, and stored in the model's config (run.presence).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "engine/run/pipeline.h"

namespace yelan::run {

struct PresenceSample {
  double share = 0;    // the mask's share of the frame on this tick
  bool person = false;  // the truth: the recording has a dancer
  std::string recording;  // its name, whose conditions (lighting, background, pan, ...) the report splits by
  // The rest of what the tick's pose says (Pose's fields of the same names), for studies of
  // what else could tell a dancer from an empty scene.
  std::int64_t t_us = 0;
  float mask_mean_p = 0, mask_blob = 0, mask_score = 0, pose_confidence = 0;
  bool mask_ran = false;
};

// The samples as CSV, one tick a row (recording, t_us, person, share, the other cues),
// written atomically.
void write_presence_ticks(const std::string& path, const std::vector<PresenceSample>& samples);

struct PresenceFit {
  double a = 0, b = 0;
  double log_loss = 0;  // class-balanced mean negative log-likelihood at the fit
};

// Logistic regression of person on ln(share + 0.001), smoothed over each recording's ticks
// with time constant tau_s as the pipeline smooths it (PresenceSmoother; the samples of a
// recording in time order, the smoothing starting at its first sample), both classes
// weighted equally (a dataset's share of empty scenes says nothing of how often a stage is
// empty), Newton's method with a little ridge so that separable data still gives finite
// numbers. a is kept >= 0 (more mask never means less person). Throws std::invalid_argument
// without both classes.
PresenceFit fit_presence(const std::vector<PresenceSample>& samples, double tau_s = 0);
// The class-balanced mean negative log-likelihood of P(person) = sigmoid(a x + b), x the
// smoothed ln(s + 0.001).
double presence_log_loss(const std::vector<PresenceSample>& samples, double a, double b, double tau_s = 0);
// Each sample's smoothed feature (a new recording wherever the name changes or time goes back).
std::vector<double> presence_features(const std::vector<PresenceSample>& samples, double tau_s);

// Seconds until the verdict is the one the share `to` gives, after the share steps from
// `from` to `to` and stays (smoothing alone, ticks taken as continuous): 0 where the verdict
// at `from` is already that one, infinity where the smoothed P never crosses 0.5.
double presence_latency_s(double a, double b, double tau_s, double from, double to);

// The largest change in P(person) between calibrations x and y over the shares a mask can
// cover (1e-4 .. 1).
double presence_distance(const std::array<double, 2>& x, const std::array<double, 2>& y);

// The calibration a pipeline should run under so that refitting on its own ticks moves
// P(person) by less than `tolerance`: the look-again rule reads the calibration, so the
// ticks depend on it. `refit(ab)` runs the ticks under ab and returns the fit to them.
// The first rerun takes the fit as it is; later ones move halfway, since a fit can flip
// between two calibrations whose ticks each fit the other. At most `max_reruns` reruns.
struct PresenceSettle {
  std::array<double, 2> used;  // the calibration the last run ran under
  PresenceFit fit;             // the fit to that run's ticks
  int reruns = 0;
  double moved = 0;  // presence_distance(used, fit)
};
PresenceSettle settle_presence(const std::array<double, 2>& start, const PresenceFit& first_fit,
                               const std::function<PresenceFit(const std::array<double, 2>&)>& refit,
                               double tolerance, int max_reruns);

struct PresenceReport {
  std::uint64_t person_ticks = 0, empty_ticks = 0;
  double hit_rate = 0;          // share of person ticks called person
  double false_alarm_rate = 0;  // share of empty ticks called person
  // Reliability: per bin of predicted P (10 bins), ticks, mean predicted P and the share
  // that truly had a person, both classes weighing half (as in the fit).
  struct Bin {
    std::uint64_t n = 0;
    double predicted = 0, observed = 0;
  };
  std::vector<Bin> bins;
  double expected_calibration_error = 0;  // tick-weighted mean |predicted - observed|
  // Per condition named in the recordings' names (low, static, pan, flicker, ...): ticks and
  // those called person, dancer and empty scenes apart.
  struct Condition {
    std::uint64_t person_ticks = 0, person_called = 0, empty_ticks = 0, empty_called = 0;
  };
  std::map<std::string, Condition> by_condition;
};

PresenceReport presence_report(const std::vector<PresenceSample>& samples, double a, double b, double threshold, double tau_s = 0);
void print_presence_report(const PresenceReport& r, std::ostream& out);

// The simulator's condition words in a recording's name (yelan sim --dataset names files
// SPLIT[-empty|-room|-dancer-room]-NNNNN-[who-clip-]VIEW-LIGHT-BACKGROUND[-occluded][-flicker]
// [-clutter][-pan|-shake|-sweep]): the view (front, back, left, right), low, static, clutter,
// sweep, ...
std::vector<std::string> conditions_in(const std::string& name);
// One tick's verdict counted under each condition its recording's name says.
void count_by_condition(std::map<std::string, PresenceReport::Condition>& by_condition, const std::string& recording,
                        bool person, bool called);
// "    low       dancer 99.0% of 300; empty 2.0% of 100" per condition.
void print_presence_by_condition(const std::map<std::string, PresenceReport::Condition>& by_condition, std::ostream& out);

// Ticks of the recordings (*.yelan.h5, dancer or empty scenes) run through the pipeline as
// `yelan run` does with options `run` (ticks at run.rate_hz from time 0, its early exit), at
// most `seconds` of each; the first `skip_s` (the TORE still filling) are left out. head_depths, when given,
// receives for every pose of a dancer recording whose head is in the picture the pair
// (true head depth, the pipeline's estimate), in mm.
std::vector<PresenceSample> presence_samples(const std::string& weights, const std::vector<std::string>& recordings,
                                             const RunOptions& run, double seconds, double skip_s, std::ostream& progress,
                                             std::vector<std::pair<double, double>>* head_depths = nullptr);

// The factor that, multiplied into a model's depth estimates, makes their median error
// vanish: the median of truth / estimate (1 without pairs).
double fit_depth_scale(const std::vector<std::pair<double, double>>& head_depths);

}  // namespace yelan::run
