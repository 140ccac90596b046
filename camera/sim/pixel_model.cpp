// DVS pixel model: see pixel_model.h. The per-step work is split in two: a branch-free loop
// over each chunk of a row that advances every pixel and flags the few that emit something,
// then a scalar pass over the flagged pixels that places their events in time.
#include "camera/sim/pixel_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "camera/sim/rng.h"
#include "kernels/vmath.h"

namespace yelan::camera::sim {

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr float kMaxIntensity = 1e9f;  // caps the log so one step's crossings stay bounded
constexpr int kChunk = 256;            // pixels per vector pass; scratch stays in L1
constexpr double kNever = -1e300;      // "last event" before any event

// RNG streams: each kind of draw has its own, so adding one never shifts another.
enum : std::uint64_t {
  kStreamThrOn = 0x7069786f6e,  // "pixon"
  kStreamThrOff,
  kStreamLeakRate,
  kStreamLeakPhase,
  kStreamHot,
  kStreamNoiseWait,
  kStreamNoiseKind,
};

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("PixelModel: " + what);
}

void validate(const PixelParams& p) {
  auto finite_ge = [](double v, double lo) { return std::isfinite(v) && v >= lo; };
  require(finite_ge(p.pos_threshold, 0.01), "pos_threshold must be >= 0.01");
  require(finite_ge(p.neg_threshold, 0.01), "neg_threshold must be >= 0.01");
  require(finite_ge(p.sigma_threshold, 0), "sigma_threshold must be >= 0");
  require(finite_ge(p.cutoff_hz, 0), "cutoff_hz must be >= 0");
  require(finite_ge(p.cutoff_floor_dn, 0), "cutoff_floor_dn must be >= 0");
  require(finite_ge(p.refractory_s, 0), "refractory_s must be >= 0");
  require(finite_ge(p.leak_rate_hz, 0), "leak_rate_hz must be >= 0");
  require(finite_ge(p.leak_rate_cov_decades, 0) && p.leak_rate_cov_decades <= 2,
          "leak_rate_cov_decades must be in [0, 2]");
  require(finite_ge(p.shot_noise_rate_hz, 0), "shot_noise_rate_hz must be >= 0");
  require(finite_ge(p.shot_noise_bright_factor, 0) && p.shot_noise_bright_factor <= 1,
          "shot_noise_bright_factor must be in [0, 1]");
  require(finite_ge(p.hot_pixel_fraction, 0) && p.hot_pixel_fraction <= 1,
          "hot_pixel_fraction must be in [0, 1]");
  require(finite_ge(p.hot_pixel_rate_hz, 0), "hot_pixel_rate_hz must be >= 0");
  require(finite_ge(p.lin_log_knee, 1) && p.lin_log_knee <= 1e6,
          "lin_log_knee must be in [1, 1e6]");
}

// Exponential(1) from a counter draw; never 0, so a pixel's hazard is always positive.
double exp1(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  const double u = (double(hash64(seed, stream, index) >> 11) + 0.5) * 0x1.0p-53;
  return -std::log(u);
}

std::uint64_t noise_key(std::size_t pixel, std::uint32_t count) {
  return (std::uint64_t(pixel) << 32) | count;
}

std::int64_t to_us(double t_s) { return std::llround(t_s * 1e6); }

}  // namespace

PixelParams pixel_params_clean() {
  PixelParams p;
  p.sigma_threshold = 0;
  p.cutoff_hz = 0;
  p.refractory_s = 0;
  p.leak_rate_hz = 0;
  p.shot_noise_rate_hz = 0;
  p.hot_pixel_fraction = 0;
  return p;
}

PixelParams pixel_params_davis346() { return PixelParams{}; }

PixelParams pixel_params_noisy() {
  PixelParams p;
  p.sigma_threshold = 0.05;
  p.cutoff_hz = 30;
  p.refractory_s = 0.01;
  p.leak_rate_hz = 0.1;
  p.shot_noise_rate_hz = 5;
  return p;
}

double lin_log(double intensity, double knee) {
  return intensity <= knee ? intensity * std::log(knee) / knee : std::log(intensity);
}

double lowpass_alpha(double intensity, double dt_s, const PixelParams& p) {
  if (p.cutoff_hz <= 0) return 1;
  const double cutoff = p.cutoff_hz * (intensity + p.cutoff_floor_dn) / (255 + p.cutoff_floor_dn);
  return 1 - std::exp(-dt_s * kTwoPi * cutoff);
}

double shot_noise_rate(double intensity, const PixelParams& p) {
  const double f = std::clamp(intensity, 0.0, 255.0) / 255;
  return p.shot_noise_rate_hz * (1 - (1 - p.shot_noise_bright_factor) * f);
}

PixelModel::PixelModel(int width, int height, const PixelParams& params, std::uint64_t seed)
    : width_(width), height_(height), params_(params), seed_(seed) {
  require(width >= 1 && width <= 65536 && height >= 1 && height <= 65536,
          "width and height must be in 1..65536, got " + std::to_string(width) + "x" +
              std::to_string(height));
  validate(params);
  lin_slope_ = float(std::log(params.lin_log_knee) / params.lin_log_knee);
  const std::size_t n = std::size_t(width) * height;
  lp_.assign(n, 0.f);
  diff_.assign(n, 0.f);
  thr_on_.resize(n);
  thr_off_.resize(n);
  leak_.resize(n);
  hazard_.assign(n, std::numeric_limits<double>::infinity());
  noise_count_.assign(n, 0);
  last_event_s_.assign(n, kNever);
  hot_.assign(n, 0);
  hot_row_begin_.assign(std::size_t(height) + 1, 0);

  // Log-normal leak-rate spread with its mean held at 1, so leak_rate_hz is the mean rate.
  const double sl = std::log(10.0) * params.leak_rate_cov_decades;
  for (std::size_t i = 0; i < n; ++i) {
    const double on = params.pos_threshold + params.sigma_threshold * normal01(seed, kStreamThrOn, i);
    const double off = params.neg_threshold + params.sigma_threshold * normal01(seed, kStreamThrOff, i);
    thr_on_[i] = float(std::max(on, 0.01));
    thr_off_[i] = float(std::max(off, 0.01));
    const double spread = std::exp(sl * normal01(seed, kStreamLeakRate, i) - 0.5 * sl * sl);
    // The reference drifts down by one ON threshold per leak period.
    leak_[i] = float(params.leak_rate_hz * spread * thr_on_[i]);
    hot_[i] = uniform01(seed, kStreamHot, i) < params.hot_pixel_fraction;
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x)
      if (hot_[index(x, y)]) hot_x_.push_back(std::uint16_t(x));
    hot_row_begin_[y + 1] = int(hot_x_.size());
  }
  row_events_.resize(height);
  row_stats_.resize(height);
  const auto& vm = kernels::vmath_kernels();
  vlog_ = vm.log;
  vexp_ = vm.exp;
}

double PixelModel::noise_scale(std::size_t i) const {
  // v2e: a pixel with a lower threshold than nominal sees proportionally more shot noise.
  return 0.5 * (params_.pos_threshold / thr_on_[i] + params_.neg_threshold / thr_off_[i]);
}

void PixelModel::lin_log_chunk(const float* in, int n, float* clamped, float* log) const {
  const float knee = float(params_.lin_log_knee);
  for (int i = 0; i < n; ++i) {
    float c = in[i] > 0.f ? in[i] : 0.f;  // NaN and negatives -> 0
    c = c < kMaxIntensity ? c : kMaxIntensity;
    clamped[i] = c;
    log[i] = c > knee ? c : knee;
  }
  vlog_(log, log, std::size_t(n));
  for (int i = 0; i < n; ++i) log[i] = clamped[i] <= knee ? clamped[i] * lin_slope_ : log[i];
}

void PixelModel::reset(const float* intensity, double t_s) {
  require(intensity != nullptr, "reset: intensity is null");
  require(std::isfinite(t_s), "reset: time is not finite");
  const bool noisy = params_.shot_noise_rate_hz > 0 ||
                     (params_.hot_pixel_fraction > 0 && params_.hot_pixel_rate_hz > 0);
  const std::uint64_t epoch = epoch_++;
  alignas(64) float clamped[kChunk], log[kChunk];
  for (int y = 0; y < height_; ++y) {
    for (int x0 = 0; x0 < width_; x0 += kChunk) {
      const int n = std::min(kChunk, width_ - x0);
      const std::size_t base = index(x0, y);
      lin_log_chunk(intensity + base, n, clamped, log);
      for (int k = 0; k < n; ++k) {
        const std::size_t i = base + k;
        lp_[i] = log[k];
        // A random leak phase, so leak events flow from the start instead of all pixels
        // reaching their first threshold together.
        diff_[i] = params_.leak_rate_hz > 0
                       ? float(uniform01(seed_, kStreamLeakPhase ^ (epoch << 40), i)) * thr_on_[i]
                       : 0.f;
        if (noisy) {
          hazard_[i] = exp1(seed_, kStreamNoiseWait, noise_key(i, noise_count_[i])) / noise_scale(i);
          ++noise_count_[i];
        }
        last_event_s_[i] = kNever;
      }
    }
  }
  stats_ = PixelStats{};
  ready_ = true;
}

void PixelModel::step(const float* intensity, double t0_s, double t1_s, std::vector<Event>& out) {
  if (!ready_) throw std::logic_error("PixelModel::step before reset");
  require(intensity != nullptr, "step: intensity is null");
  require(std::isfinite(t0_s) && std::isfinite(t1_s) && t1_s > t0_s,
          "step: need finite times with t1 > t0, got " + std::to_string(t0_s) + " .. " +
              std::to_string(t1_s));
  StepSpan span;
  span.t0_s = t0_s;
  span.dt_s = t1_s - t0_s;
  const std::int64_t t0_us = to_us(t0_s), t1_us = to_us(t1_s);
  span.hi_us = t1_us;
  span.lo_us = std::min(t0_us + 1, t1_us);
  const int rows = height_;
  // Rows are independent and every draw is keyed by pixel, so the split over threads
  // cannot change the result; small frames are not worth waking the team for.
#pragma omp parallel for schedule(static) if (std::size_t(width_) * height_ >= 16384)
  for (int y = 0; y < rows; ++y) {
    row_events_[y].clear();
    row_stats_[y] = RowStats{};
    step_row(y, intensity + index(0, y), span, row_events_[y], row_stats_[y]);
  }
  for (const RowStats& s : row_stats_) {
    stats_.signal += s.signal;
    stats_.shot += s.shot;
    stats_.hot += s.hot;
    stats_.refractory_dropped += s.dropped;
  }
  merge_rows(t0_us, t1_us, out);
}

void PixelModel::step_row(int y, const float* in, const StepSpan& span, std::vector<Event>& buf,
                          RowStats& st) {
  const PixelParams& p = params_;
  const float dt = float(span.dt_s);
  const bool lowpass = p.cutoff_hz > 0;
  // alpha = 1 - exp(gain * (I + floor)): the exact first-order response over dt.
  const float gain = float(-span.dt_s * kTwoPi * p.cutoff_hz / (255 + p.cutoff_floor_dn));
  const float floor_dn = float(p.cutoff_floor_dn);
  // Shot-noise hazard drop over the step: linear in intensity up to 255.
  const double shot0 = p.shot_noise_rate_hz * span.dt_s;
  const double shot_slope = p.shot_noise_rate_hz * (1 - p.shot_noise_bright_factor) / 255 * span.dt_s;
  const int hot_begin = hot_row_begin_[y], hot_end = hot_row_begin_[y + 1];

  alignas(64) float clamped[kChunk], log[kChunk], alpha[kChunk], delta[kChunk];
  alignas(64) double drop[kChunk];
  alignas(64) int flag[kChunk];
  for (int x0 = 0; x0 < width_; x0 += kChunk) {
    const int n = std::min(kChunk, width_ - x0);
    const std::size_t base = index(x0, y);
    lin_log_chunk(in + x0, n, clamped, log);
    if (lowpass) {
      for (int k = 0; k < n; ++k) alpha[k] = gain * (clamped[k] + floor_dn);
      vexp_(alpha, alpha, std::size_t(n));
      for (int k = 0; k < n; ++k) alpha[k] = 1.f - alpha[k];
    } else {
      std::fill_n(alpha, n, 1.f);
    }
    std::fill_n(flag, n, 0);
    for (int h = hot_begin; h < hot_end; ++h)  // hot pixels always take the event pass
      if (hot_x_[h] >= x0 && hot_x_[h] < x0 + n) flag[hot_x_[h] - x0] = 1;

    float* __restrict lp = lp_.data() + base;
    float* __restrict diff = diff_.data() + base;
    double* __restrict haz = hazard_.data() + base;
    const float* __restrict on = thr_on_.data() + base;
    const float* __restrict off = thr_off_.data() + base;
    const float* __restrict leak = leak_.data() + base;
    int any = 0;
    for (int k = 0; k < n; ++k) {
      const float old = lp[k];
      const float now = old + alpha[k] * (log[k] - old);
      const float d = (now - old) + leak[k] * dt;
      const float dn = diff[k] + d;
      const double hd = shot0 - shot_slope * double(std::min(clamped[k], 255.f));
      const double hn = haz[k] - hd;
      const int f = flag[k] | int(dn >= on[k]) | int(dn <= -off[k]) | int(hn <= 0);
      lp[k] = now;
      // Flagged pixels keep their old state for the event pass to advance.
      diff[k] = f ? diff[k] : dn;
      haz[k] = f ? haz[k] : hn;
      delta[k] = d;
      drop[k] = hd;
      flag[k] = f;
      any |= f;
    }
    if (!any) continue;
    for (int k = 0; k < n; ++k)
      if (flag[k]) pixel_events(x0 + k, y, delta[k], drop[k], span, buf, st);
  }
}

// Places one pixel's events inside the step. Two time-ordered sources are merged: the
// threshold crossings of diff (linear in time over the step: ESIM), and the noise events
// where the pixel's hazard clock runs out. Every event then passes the refractory check.
void PixelModel::pixel_events(int x, int y, float delta, double hazard_drop, const StepSpan& span,
                              std::vector<Event>& buf, RowStats& st) {
  const std::size_t i = index(x, y);
  const float d0 = diff_[i], on = thr_on_[i], off = thr_off_[i];
  float rest = d0 + delta;  // diff at the step's end, less the thresholds already crossed
  const int dir = rest >= on ? 1 : (rest <= -off ? -1 : 0);
  int crossing = 1;  // index of the next crossing

  // Noise: shot noise at the nominal-threshold rate (scaled into hazard units by the
  // pixel's noise_scale on each refill), plus the hot-pixel rate for hot pixels.
  const double scale = noise_scale(i);
  const double shot_rate = hazard_drop / span.dt_s * scale;  // this pixel's shot events/s
  const double hot_rate = hot_[i] ? params_.hot_pixel_rate_hz : 0.0;
  const double total_drop = hazard_drop + hot_rate / scale * span.dt_s;
  const double hot_share = hot_rate > 0 ? hot_rate / (hot_rate + shot_rate) : 0.0;
  const double on_share = (1 / on) / (1 / on + 1 / off);
  double hazard = hazard_[i];  // hazard left at the step's start, plus the refills so far

  for (;;) {
    double s_sig = 2, s_noise = 2;
    // delta is nonzero whenever dir is (diff started inside the thresholds).
    if (dir > 0 && rest >= on) s_sig = delta != 0 ? (double(crossing) * on - d0) / delta : 0;
    if (dir < 0 && rest <= -off) s_sig = delta != 0 ? (-double(crossing) * off - d0) / delta : 0;
    if (total_drop > 0 && hazard <= total_drop) s_noise = hazard / total_drop;
    if (s_sig > 1.5 && s_noise > 1.5) break;

    std::uint8_t polarity;
    enum { kSignal, kShot, kHot } kind;
    double s;
    if (s_sig <= s_noise) {
      s = s_sig;
      kind = kSignal;
      polarity = dir > 0;
      rest -= dir > 0 ? on : -off;  // the reference moves even when refractory drops it
      ++crossing;
    } else {
      s = s_noise;
      const std::uint64_t key = noise_key(i, noise_count_[i]);
      const double u = uniform01(seed_, kStreamNoiseKind, key);
      if (u < hot_share) {
        kind = kHot;
        polarity = 1;
      } else {
        kind = kShot;
        polarity = (u - hot_share) < on_share * (1 - hot_share);
      }
      hazard += exp1(seed_, kStreamNoiseWait, key) / scale;
      ++noise_count_[i];
    }
    s = std::clamp(s, 0.0, 1.0);
    const double t = span.t0_s + s * span.dt_s;
    if (t - last_event_s_[i] < params_.refractory_s) {
      ++st.dropped;
      continue;
    }
    last_event_s_[i] = t;
    const std::int64_t t_us = std::clamp(to_us(t), span.lo_us, span.hi_us);
    buf.push_back(Event{t_us, std::uint16_t(x), std::uint16_t(y), polarity});
    if (kind == kSignal) ++st.signal;
    else if (kind == kShot) ++st.shot;
    else ++st.hot;
  }
  diff_[i] = rest;
  hazard_[i] = total_drop > 0 ? hazard - total_drop : hazard;
}

// Rows hold their events in (y, x, t) order; a stable counting sort on t then gives the
// stream's (t, y, x) order without comparing events.
void PixelModel::merge_rows(std::int64_t t0_us, std::int64_t t1_us, std::vector<Event>& out) {
  std::size_t n = 0;
  for (const auto& r : row_events_) n += r.size();
  if (n == 0) return;
  const std::size_t first = out.size();
  const std::int64_t lo = std::min(t0_us + 1, t1_us);
  const std::uint64_t span = std::uint64_t(t1_us - lo) + 1;
  if (span <= std::max<std::uint64_t>(1u << 16, 4 * n)) {
    histogram_.assign(span + 1, 0);
    for (const auto& r : row_events_)
      for (const Event& e : r) ++histogram_[std::size_t(e.t - lo) + 1];
    for (std::size_t b = 1; b <= span; ++b) histogram_[b] += histogram_[b - 1];
    out.resize(first + n);
    for (const auto& r : row_events_)
      for (const Event& e : r) out[first + histogram_[std::size_t(e.t - lo)]++] = e;
    return;
  }
  merged_.clear();
  for (const auto& r : row_events_) merged_.insert(merged_.end(), r.begin(), r.end());
  std::stable_sort(merged_.begin(), merged_.end(),
                   [](const Event& a, const Event& b) { return a.t < b.t; });
  out.insert(out.end(), merged_.begin(), merged_.end());
}

double PixelModel::max_log_change(const float* next) const {
  if (!ready_) throw std::logic_error("PixelModel::max_log_change before reset");
  require(next != nullptr, "max_log_change: intensity is null");
  double best = 0;
  const int rows = height_;
#pragma omp parallel for schedule(static) reduction(max : best) \
    if (std::size_t(width_) * height_ >= 16384)
  for (int y = 0; y < rows; ++y) {
    alignas(64) float clamped[kChunk], log[kChunk];
    for (int x0 = 0; x0 < width_; x0 += kChunk) {
      const int n = std::min(kChunk, width_ - x0);
      const std::size_t base = index(x0, y);
      lin_log_chunk(next + base, n, clamped, log);
      float m = 0;
      for (int k = 0; k < n; ++k) m = std::max(m, std::fabs(log[k] - lp_[base + k]));
      best = std::max(best, double(m));
    }
  }
  return best;
}

}  // namespace yelan::camera::sim
