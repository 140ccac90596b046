#include "engine/run/presence.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <stdexcept>

#include "camera/io/event_reader.h"
#include "camera/sim/recording_windows.h"
#include "engine/run/pipeline.h"

namespace yelan::run {

namespace {

double feature(double share) { return std::log(std::max(0.0, share) + 0.001); }
double sigmoid(double z) { return 1 / (1 + std::exp(-z)); }

}  // namespace

PresenceFit fit_presence(const std::vector<PresenceSample>& samples) {
  double n_pos = 0, n_neg = 0;
  for (const auto& s : samples) (s.person ? n_pos : n_neg) += 1;
  if (n_pos == 0 || n_neg == 0)
    throw std::invalid_argument("presence calibration needs ticks with a person and ticks without (got " +
                                std::to_string(std::uint64_t(n_pos)) + " and " + std::to_string(std::uint64_t(n_neg)) + ")");
  const double w_pos = 0.5 / n_pos, w_neg = 0.5 / n_neg, ridge = 1e-4;
  double a = 1, b = 0;
  for (int it = 0; it < 100; ++it) {
    // Gradient and Hessian of the weighted log-loss (+ ridge on a) in (a, b).
    double ga = ridge * a, gb = 0, haa = ridge, hab = 0, hbb = 1e-9;
    for (const auto& s : samples) {
      const double x = feature(s.share), p = sigmoid(a * x + b), w = s.person ? w_pos : w_neg;
      const double r = w * (p - (s.person ? 1.0 : 0.0)), h = w * p * (1 - p);
      ga += r * x, gb += r;
      haa += h * x * x, hab += h * x, hbb += h;
    }
    const double det = haa * hbb - hab * hab;
    if (!(std::abs(det) > 1e-300)) break;
    const double da = (hbb * ga - hab * gb) / det, db = (haa * gb - hab * ga) / det;
    a -= da, b -= db;
    if (a < 0) a = 0;  // more mask never means less person
    if (std::abs(da) + std::abs(db) < 1e-10) break;
  }
  PresenceFit f{a, b, 0};
  for (const auto& s : samples) {
    const double p = std::clamp(sigmoid(a * feature(s.share) + b), 1e-12, 1 - 1e-12);
    f.log_loss -= (s.person ? w_pos * std::log(p) : w_neg * std::log(1 - p));
  }
  return f;
}

PresenceReport presence_report(const std::vector<PresenceSample>& samples, double a, double b, double threshold) {
  PresenceReport r;
  r.bins.resize(10);
  std::uint64_t hits = 0, alarms = 0;
  for (const auto& s : samples) {
    const double p = presence_probability(s.share, a, b);
    const bool called = p >= threshold;
    if (s.person) ++r.person_ticks, hits += called;
    else ++r.empty_ticks, alarms += called;
    auto& bin = r.bins[std::size_t(std::min(9, int(p * 10)))];
    ++bin.n;
    bin.predicted += p;
    bin.observed += s.person;
  }
  r.hit_rate = r.person_ticks ? double(hits) / double(r.person_ticks) : 0;
  r.false_alarm_rate = r.empty_ticks ? double(alarms) / double(r.empty_ticks) : 0;
  double ece = 0;
  for (auto& bin : r.bins)
    if (bin.n) {
      bin.predicted /= double(bin.n);
      bin.observed /= double(bin.n);
      ece += double(bin.n) * std::abs(bin.predicted - bin.observed);
    }
  r.expected_calibration_error = samples.empty() ? 0 : ece / double(samples.size());
  return r;
}

void print_presence_report(const PresenceReport& r, std::ostream& out) {
  out << std::fixed << std::setprecision(1) << "  ticks with a dancer called person: " << 100 * r.hit_rate << "% of "
      << r.person_ticks << "; empty ticks called person: " << 100 * r.false_alarm_rate << "% of " << r.empty_ticks
      << "; expected calibration error " << std::setprecision(3) << r.expected_calibration_error << "\n"
      << "  reliability (predicted P bin: ticks, mean predicted, share with a person):\n";
  for (std::size_t i = 0; i < r.bins.size(); ++i)
    if (r.bins[i].n)
      out << "    " << std::setprecision(1) << double(i) / 10 << "-" << double(i + 1) / 10 << ": " << r.bins[i].n << ", "
          << std::setprecision(3) << r.bins[i].predicted << ", " << r.bins[i].observed << "\n";
}

std::vector<PresenceSample> presence_samples(const std::string& weights, const std::vector<std::string>& recordings,
                                             double rate_hz, double seconds, double skip_s, std::ostream& progress) {
  std::vector<PresenceSample> out;
  RunOptions opt;
  opt.rate_hz = rate_hz;
  opt.tick_origin_us = 0;
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    const camera::sim::RecordingInfo info = camera::sim::read_recording_info(recordings[i]);
    auto reader = camera::open_event_file(recordings[i]);
    PosePipeline pipe(weights, info.camera.width, info.camera.height, opt);
    const std::int64_t end_us = info.first_event_us + std::llround(seconds * 1e6);
    const std::int64_t skip_us = info.first_event_us + std::llround(skip_s * 1e6);
    std::size_t before = out.size();
    const auto keep = [&](const Pose& p) {
      if (p.t_us >= skip_us) out.push_back({p.mask_share, info.dancer});
    };
    std::vector<camera::Event> ev;
    while (true) {
      ev.clear();
      if (reader->read_until(ev, end_us, 1 << 20) == 0) break;
      pipe.push(ev, keep);
    }
    pipe.finish(end_us, keep);
    progress << "  [" << (i + 1) << "/" << recordings.size() << "] " << info.name << (info.dancer ? "" : " (empty)") << ": "
             << (out.size() - before) << " ticks\n";
  }
  return out;
}

}  // namespace yelan::run
