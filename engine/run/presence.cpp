#include "engine/run/presence.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "camera/io/temp_file.h"
#include "camera/sim/recording_windows.h"
#include "engine/run/pipeline.h"

namespace yelan::run {

namespace {

// Both classes' weights (each half), refusing samples of one class alone.
std::array<double, 2> class_weights(const std::vector<PresenceSample>& samples) {
  double n_pos = 0, n_neg = 0;
  for (const auto& s : samples) (s.person ? n_pos : n_neg) += 1;
  if (n_pos == 0 || n_neg == 0)
    throw std::invalid_argument("presence calibration needs ticks with a person and ticks without (got " +
                                std::to_string(std::uint64_t(n_pos)) + " and " + std::to_string(std::uint64_t(n_neg)) + ")");
  return {0.5 / n_pos, 0.5 / n_neg};
}

// The weighted log-loss, computed stably (log1p of exp of the margin).
double balanced_log_loss(const std::vector<PresenceSample>& samples, const std::vector<double>& x, double a, double b,
                         double w_pos, double w_neg) {
  double l = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    const double z = a * x[i] + b, m = s.person ? z : -z;  // -log sigmoid(m)
    l += (s.person ? w_pos : w_neg) * (m > 0 ? std::log1p(std::exp(-m)) : -m + std::log1p(std::exp(m)));
  }
  return l;
}

}  // namespace

std::vector<double> presence_features(const std::vector<PresenceSample>& samples, double tau_s) {
  std::vector<double> x(samples.size());
  PresenceSmoother smooth(tau_s);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (i > 0 && samples[i].recording != samples[i - 1].recording) smooth.reset();
    x[i] = smooth.update(samples[i].share, samples[i].t_us);
  }
  return x;
}

double presence_latency_s(double a, double b, double tau_s, double from, double to) {
  const double x0 = presence_feature(from), x1 = presence_feature(to);
  if (a <= 0 || x0 == x1) return std::numeric_limits<double>::infinity();
  const double f = (-b / a - x0) / (x1 - x0);  // the part of the step the smoothed x must cover
  if (f <= 0) return 0;
  if (f >= 1) return std::numeric_limits<double>::infinity();
  return tau_s > 0 ? -tau_s * std::log(1 - f) : 0;
}

double presence_distance(const std::array<double, 2>& x, const std::array<double, 2>& y) {
  double most = 0;
  for (double s = 1e-4; s <= 1; s *= 1.25)
    most = std::max(most, std::abs(presence_probability(s, x[0], x[1]) - presence_probability(s, y[0], y[1])));
  return most;
}

PresenceSettle settle_presence(const std::array<double, 2>& start, const PresenceFit& first_fit,
                               const std::function<PresenceFit(const std::array<double, 2>&)>& refit,
                               double tolerance, int max_reruns) {
  PresenceSettle r{start, first_fit, 0, presence_distance(start, {first_fit.a, first_fit.b})};
  while (r.reruns < max_reruns && r.moved >= tolerance) {
    const std::array<double, 2> fitted = {r.fit.a, r.fit.b};
    r.used = r.reruns == 0 ? fitted
                           : std::array<double, 2>{0.5 * (r.used[0] + fitted[0]), 0.5 * (r.used[1] + fitted[1])};
    r.fit = refit(r.used);
    ++r.reruns;
    r.moved = presence_distance(r.used, {r.fit.a, r.fit.b});
  }
  return r;
}

double presence_log_loss(const std::vector<PresenceSample>& samples, double a, double b, double tau_s) {
  const auto w = class_weights(samples);
  return balanced_log_loss(samples, presence_features(samples, tau_s), a, b, w[0], w[1]);
}

PresenceFit fit_presence(const std::vector<PresenceSample>& samples, double tau_s) {
  const auto [w_pos, w_neg] = class_weights(samples);
  const std::vector<double> xs = presence_features(samples, tau_s);
  const double ridge = 1e-4;
  const auto loss = [&](double a, double b) { return 0.5 * ridge * a * a + balanced_log_loss(samples, xs, a, b, w_pos, w_neg); };
  double a = 1, b = 0, cur = loss(a, b);
  for (int it = 0; it < 200; ++it) {
    double ga = ridge * a, gb = 0, haa = ridge, hab = 0, hbb = 1e-9;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const auto& s = samples[i];
      const double x = xs[i], p = presence_probability_of_feature(x, a, b), w = s.person ? w_pos : w_neg;
      const double r = w * (p - (s.person ? 1.0 : 0.0)), h = w * p * (1 - p);
      ga += r * x, gb += r;
      haa += h * x * x, hab += h * x, hbb += h;
    }
    const double det = haa * hbb - hab * hab;
    double da = ga, db = gb;  // the gradient, where the Hessian is singular
    if (std::abs(det) > 1e-300) da = (hbb * ga - hab * gb) / det, db = (haa * gb - hab * ga) / det;
    // Newton's step, halved until the loss falls (plain Newton overshoots from a poor start).
    bool moved = false;
    for (double t = 1; t > 1e-8; t *= 0.5) {
      const double na = std::max(0.0, a - t * da), nb = b - t * db, l = loss(na, nb);  // more mask never means less person
      if (l < cur) {
        moved = cur - l > 1e-13;
        a = na, b = nb, cur = l;
        break;
      }
    }
    if (!moved) break;
  }
  PresenceFit f{a, b, 0};
  f.log_loss = cur - 0.5 * ridge * a * a;
  return f;
}

std::vector<std::string> conditions_in(const std::string& name) {
  static const char* const kWords[] = {"front", "back",    "left",     "right",   "low", "medium", "high", "static",
                                       "dynamic", "occluded", "flicker", "clutter", "pan", "shake",  "sweep"};
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= name.size()) {
    const std::size_t end = std::min(name.find_first_of("-_.", start), name.size());
    const std::string word = name.substr(start, end - start);
    for (const char* w : kWords)
      if (word == w) out.push_back(word);
    start = end + 1;
  }
  return out;
}

void count_by_condition(std::map<std::string, PresenceReport::Condition>& by_condition, const std::string& recording,
                        bool person, bool called) {
  for (const std::string& c : conditions_in(recording)) {
    auto& k = by_condition[c];
    (person ? k.person_ticks : k.empty_ticks) += 1;
    (person ? k.person_called : k.empty_called) += called;
  }
}

PresenceReport presence_report(const std::vector<PresenceSample>& samples, double a, double b, double threshold, double tau_s) {
  PresenceReport r;
  r.bins.resize(10);
  std::uint64_t hits = 0, alarms = 0;
  for (const auto& s : samples) (s.person ? r.person_ticks : r.empty_ticks) += 1;
  // Each class weighs half, as in the fit: the probability is calibrated for a stage where
  // a person is there half of the time, whatever the dataset's share of empty scenes.
  const double w_pos = r.person_ticks ? 0.5 / double(r.person_ticks) : 0, w_neg = r.empty_ticks ? 0.5 / double(r.empty_ticks) : 0;
  std::vector<double> weight(r.bins.size(), 0.0);
  const std::vector<double> xs = presence_features(samples, tau_s);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto& s = samples[i];
    const double p = presence_probability_of_feature(xs[i], a, b), w = s.person ? w_pos : w_neg;
    const bool called = p >= threshold;
    (s.person ? hits : alarms) += called;
    count_by_condition(r.by_condition, s.recording, s.person, called);
    const std::size_t k = std::size_t(std::min(9, int(p * 10)));
    ++r.bins[k].n;
    weight[k] += w;
    r.bins[k].predicted += w * p;
    r.bins[k].observed += s.person ? w : 0;
  }
  r.hit_rate = r.person_ticks ? double(hits) / double(r.person_ticks) : 0;
  r.false_alarm_rate = r.empty_ticks ? double(alarms) / double(r.empty_ticks) : 0;
  double ece = 0, total = 0;
  for (std::size_t k = 0; k < r.bins.size(); ++k)
    if (weight[k] > 0) {
      r.bins[k].predicted /= weight[k];
      r.bins[k].observed /= weight[k];
      ece += weight[k] * std::abs(r.bins[k].predicted - r.bins[k].observed);
      total += weight[k];
    }
  r.expected_calibration_error = total > 0 ? ece / total : 0;
  return r;
}

void print_presence_report(const PresenceReport& r, std::ostream& out) {
  out << std::fixed << std::setprecision(1) << "  ticks with a dancer called person: " << 100 * r.hit_rate << "% of "
      << r.person_ticks << "; empty ticks called person: " << 100 * r.false_alarm_rate << "% of " << r.empty_ticks
      << "; expected calibration error " << std::setprecision(3) << r.expected_calibration_error << "\n"
      << " (classes weighted equally)\n"
      << "  reliability (predicted P bin: ticks, mean predicted, share with a person; classes weighted equally):\n";
  for (std::size_t i = 0; i < r.bins.size(); ++i)
    if (r.bins[i].n)
      out << "    " << std::setprecision(1) << double(i) / 10 << "-" << double(i + 1) / 10 << ": " << r.bins[i].n << ", "
          << std::setprecision(3) << r.bins[i].predicted << ", " << r.bins[i].observed << "\n";
  print_presence_by_condition(r.by_condition, out);
}

void print_presence_by_condition(const std::map<std::string, PresenceReport::Condition>& by_condition, std::ostream& out) {
  if (by_condition.empty()) return;
  out << std::fixed << "  by condition (dancer ticks called person; empty ticks called person):\n";
  for (const auto& [name, c] : by_condition) {
    out << "    " << std::left << std::setw(9) << name << std::right << std::setprecision(1);
    if (c.person_ticks) out << " dancer " << 100 * double(c.person_called) / double(c.person_ticks) << "% of " << c.person_ticks;
    else out << " dancer -";
    if (c.empty_ticks) out << "; empty " << 100 * double(c.empty_called) / double(c.empty_ticks) << "% of " << c.empty_ticks;
    else out << "; empty -";
    out << "\n";
  }
}

void write_presence_ticks(const std::string& path, const std::vector<PresenceSample>& samples) {
  std::ostringstream o;
  o << "recording,t_us,person,share,mask_mean_p,mask_blob,mask_score,pose_confidence,mask_ran\n";
  o.precision(6);
  for (const auto& s : samples)
    o << s.recording << "," << s.t_us << "," << (s.person ? 1 : 0) << "," << s.share << "," << s.mask_mean_p << ","
      << s.mask_blob << "," << s.mask_score << "," << s.pose_confidence << "," << (s.mask_ran ? 1 : 0) << "\n";
  camera::write_file_atomically(path, o.str());
}

double fit_depth_scale(const std::vector<std::pair<double, double>>& head_depths) {
  std::vector<double> r;
  for (const auto& [truth, est] : head_depths)
    if (est > 0 && truth > 0) r.push_back(truth / est);
  return r.empty() ? 1 : percentile(r, 0.5);
}

std::vector<PresenceSample> presence_samples(const std::string& weights, const std::vector<std::string>& recordings,
                                             const RunOptions& run, double seconds, double skip_s, std::ostream& progress,
                                             std::vector<std::pair<double, double>>* head_depths) {
  std::vector<PresenceSample> out;
  RunOptions opt = run;
  opt.tick_origin_us = 0;
  opt.stage1_cues = true;
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    const camera::sim::RecordingInfo info = camera::sim::read_recording_info(recordings[i]);
    PosePipeline pipe(weights, info.camera.width, info.camera.height, opt);
    const std::int64_t end_us = info.first_event_us + std::llround(seconds * 1e6);
    const std::int64_t skip_us = info.first_event_us + std::llround(skip_s * 1e6);
    std::size_t before = out.size();
    const auto keep = [&](const Pose& p) {
      if (p.t_us < skip_us) return;
      out.push_back({p.mask_share, info.dancer, info.name, p.t_us, p.mask_mean_p, p.mask_blob, p.mask_score,
                     p.pose_confidence, p.mask_ran});
      if (head_depths && info.dancer && p.head_depth_mm > 0) {
        camera::sim::Joints13 joints;
        std::array<std::uint8_t, camera::sim::kJointCount> valid{};
        camera::sim::label_at(info, p.t_us, joints, valid);
        if (valid[0] && joints[0].z() > 1) head_depths->push_back({joints[0].z(), p.head_depth_mm});
      }
    };
    run_file(pipe, recordings[i], end_us, keep);
    progress << "  [" << (i + 1) << "/" << recordings.size() << "] " << info.name << (info.dancer ? "" : " (empty)") << ": "
             << (out.size() - before) << " ticks\n";
  }
  return out;
}

}  // namespace yelan::run
