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
  kStreamHotWait,
};
constexpr double kMaxTimeS = 1e9;  // microsecond timestamps stay far inside int64
constexpr double kRebaseS = 64;  // float seconds stay within 4 us up to here

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

// Exponential(1) from a counter draw; never 0, so a clock always moves forward.
double exp1(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  const double u = (double(hash64(seed, stream, index) >> 11) + 0.5) * 0x1.0p-53;
  return -std::log(u);
}

std::uint64_t noise_key(std::size_t pixel, std::uint32_t count) {
  return (std::uint64_t(pixel) << 32) | count;
}

std::int64_t to_us(double t_s) { return std::llround(t_s * 1e6); }

// The per-pixel hot loop: advances the low-pass and diff of n pixels and flags those that
// cross a threshold or reach their shot-noise clock (or were flagged already: hot pixels).
// Flagged pixels keep their old diff for the event pass. Branch-free, so it vectorises.
int advance_chunk(int n, float dt, float t1_rel, const float* __restrict alpha,
                  const float* __restrict log, float* __restrict lp, float* __restrict diff,
                  const float* __restrict on, const float* __restrict off,
                  const float* __restrict leak, const float* __restrict shot,
                  float* __restrict delta, int* __restrict flag) {
  int any = 0;
  for (int k = 0; k < n; ++k) {
    const float old = lp[k];
    const float now = old + alpha[k] * (log[k] - old);
    const float d = (now - old) + leak[k] * dt;
    const float dn = diff[k] + d;
    const int f = flag[k] | (dn >= on[k]) | (dn <= -off[k]) | (shot[k] <= t1_rel);
    lp[k] = now;
    diff[k] = f ? diff[k] : dn;
    delta[k] = d;
    flag[k] = f;
    any |= f;
  }
  return any;
}

}  // namespace

// The presets set each noise field by name: tables of values, deliberately alike.
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
  next_shot_.assign(n, std::numeric_limits<float>::infinity());
  shot_count_.assign(n, 0);
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
  hot_next_.assign(hot_x_.size(), std::numeric_limits<double>::infinity());
  hot_count_.assign(hot_x_.size(), 0);
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

// Waiting time to the next event of a Poisson clock at `rate`; +inf when it never ticks.
double PixelModel::draw_wait(std::uint64_t stream, std::size_t pixel, std::uint32_t count,
                             double rate) const {
  if (!(rate > 0)) return std::numeric_limits<double>::infinity();
  return exp1(seed_, stream, noise_key(pixel, count)) / rate;
}

void PixelModel::lin_log_chunk(const float* __restrict in, int n, float* __restrict clamped,
                               float* __restrict log) const {
  const float knee = float(params_.lin_log_knee), slope = lin_slope_;  // locals: no aliasing
  for (int i = 0; i < n; ++i) {
    float c = in[i] > 0.f ? in[i] : 0.f;  // NaN and negatives -> 0
    c = c < kMaxIntensity ? c : kMaxIntensity;
    clamped[i] = c;
    log[i] = c > knee ? c : knee;
  }
  vlog_(log, log, std::size_t(n));
  for (int i = 0; i < n; ++i) {
    // An arithmetic blend (exact, both terms finite): GCC will not if-convert a select here.
    const float c = clamped[i], below = float(c <= knee);
    log[i] = below * (c * slope) + (1.f - below) * log[i];
  }
}

void PixelModel::reset(const float* intensity, double t_s) {
  require(intensity != nullptr, "reset: intensity is null");
  require(std::abs(t_s) <= kMaxTimeS, "reset: time is not finite or beyond 1e9 s");
  const std::uint64_t epoch = epoch_++;
  time_base_ = t_s;
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
        const double top = params_.shot_noise_rate_hz * noise_scale(i);
        next_shot_[i] = float(draw_wait(kStreamNoiseWait, i, shot_count_[i]++, top));
        last_event_s_[i] = kNever;
      }
    }
    for (int h = hot_row_begin_[y]; h < hot_row_begin_[y + 1]; ++h)
      hot_next_[h] = t_s + draw_wait(kStreamHotWait, index(hot_x_[h], y), hot_count_[h]++,
                                     params_.hot_pixel_rate_hz);
  }
  stats_ = PixelStats{};
  ready_ = true;
}

void PixelModel::step(const float* intensity, double t0_s, double t1_s, std::vector<Event>& out) {
  if (!ready_) throw std::logic_error("PixelModel::step before reset");
  require(intensity != nullptr, "step: intensity is null");
  require(std::abs(t0_s) <= kMaxTimeS && std::abs(t1_s) <= kMaxTimeS && t1_s > t0_s,
          "step: need times within +-1e9 s with t1 > t0, got " + std::to_string(t0_s) + " .. " +
              std::to_string(t1_s));
  StepSpan span;
  span.t0_s = t0_s;
  span.t1_s = t1_s;
  span.dt_s = t1_s - t0_s;
  span.base_shift_s = 0;
  if (t1_s - time_base_ > kRebaseS) {
    span.base_shift_s = t0_s - time_base_;
    time_base_ = t0_s;
  }
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
  const float t1_rel = float(span.t1_s - time_base_);
  const int hot_begin = hot_row_begin_[y], hot_end = hot_row_begin_[y + 1];
  if (span.base_shift_s != 0)
    for (int x = 0; x < width_; ++x) {
      float& c = next_shot_[index(x, y)];
      c = float(double(c) - span.base_shift_s);
    }

  alignas(64) float clamped[kChunk], log[kChunk], alpha[kChunk], delta[kChunk];
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

    const int any = advance_chunk(n, dt, t1_rel, alpha, log, lp_.data() + base, diff_.data() + base,
                                  thr_on_.data() + base, thr_off_.data() + base,
                                  leak_.data() + base, next_shot_.data() + base, delta, flag);
    if (!any) continue;
    for (int k = 0; k < n; ++k)
      if (flag[k]) pixel_events(x0 + k, y, delta[k], clamped[k], span, buf, st);
  }
}

// Places one pixel's events inside the step, merging three time-ordered sources: the
// threshold crossings of diff (linear in time over the step: ESIM), the pixel's shot-noise
// clock and, for a hot pixel, its hot clock. Every event then passes the refractory check.
void PixelModel::pixel_events(int x, int y, float delta, float intensity, const StepSpan& span,
                              std::vector<Event>& buf, RowStats& st) {
  const std::size_t i = index(x, y);
  const float d0 = diff_[i], on = thr_on_[i], off = thr_off_[i];
  float rest = d0 + delta;  // diff at the step's end, less the thresholds already crossed
  const int dir = rest >= on ? 1 : (rest <= -off ? -1 : 0);
  int crossing = 1;  // index of the next crossing

  const float t1_rel = float(span.t1_s - time_base_);
  int hot = -1;
  for (int h = hot_row_begin_[y]; h < hot_row_begin_[y + 1]; ++h)
    if (hot_x_[h] == x) hot = h;

  auto fraction = [&](double t) { return (t - span.t0_s) / span.dt_s; };
  for (;;) {
    double s_sig = 2, s_shot = 2, s_hot = 2;
    // delta is nonzero whenever dir is (diff started inside the thresholds).
    if (dir > 0 && rest >= on) s_sig = delta != 0 ? (double(crossing) * on - d0) / delta : 0;
    if (dir < 0 && rest <= -off) s_sig = delta != 0 ? (-double(crossing) * off - d0) / delta : 0;
    if (next_shot_[i] <= t1_rel) s_shot = fraction(time_base_ + next_shot_[i]);
    if (hot >= 0 && hot_next_[hot] <= span.t1_s) s_hot = fraction(hot_next_[hot]);
    if (s_sig > 1.5 && s_shot > 1.5 && s_hot > 1.5) break;

    std::uint8_t polarity;
    std::uint64_t* counter;
    double s;
    if (s_sig <= s_shot && s_sig <= s_hot) {
      s = s_sig;
      polarity = dir > 0;
      rest -= dir > 0 ? on : -off;  // the reference moves even when refractory drops it
      ++crossing;
      counter = &st.signal;
    } else if (s_shot <= s_hot) {
      s = s_shot;
      const std::uint32_t c = shot_count_[i]++;
      const double u = uniform01(seed_, kStreamNoiseKind, noise_key(i, c));
      const double top_rate = params_.shot_noise_rate_hz * noise_scale(i);
      next_shot_[i] = float(double(next_shot_[i]) + draw_wait(kStreamNoiseWait, i, c + 1, top_rate));
      // Thinning: a candidate survives with the intensity's share of the dark rate, and is
      // ON with the pixel's ON share (the lower threshold fires more often).
      const double keep = shot_noise_rate(intensity, params_) / params_.shot_noise_rate_hz;
      if (u >= keep) continue;
      const double on_share = (1 / on) / (1 / on + 1 / off);
      polarity = u < keep * on_share;
      counter = &st.shot;
    } else {
      s = s_hot;
      hot_next_[hot] += draw_wait(kStreamHotWait, i, hot_count_[hot]++, params_.hot_pixel_rate_hz);
      polarity = 1;
      counter = &st.hot;
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
    ++*counter;
  }
  diff_[i] = rest;
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
