// The DVS pixel model of the simulator (SPEC section 4), after v2e and ESIM: rendered linear
// intensity in, events out. Per pixel it keeps a low-passed lin-log intensity and the
// difference to the memorised reference; an event fires each time that difference crosses
// the pixel's ON or OFF threshold, at the time inside the step where the (linearly
// interpolated) signal crosses it. Noise (leak, shot noise, hot pixels) is drawn from the
// counter-based RNG, so the same seed gives the same events whatever the thread count.
//
// Noise model: leak drifts each pixel's reference down at leak_rate_hz thresholds per
// second (per-pixel log-normal rate, random phase at reset), so it fires ON events through
// the same crossing logic as real changes. Shot noise and hot pixels are Poisson clocks
// per pixel, keyed by (seed, pixel, event count): their event times fall anywhere inside a
// step and their statistics do not depend on the step length. Shot and hot events do not
// move the reference; every event, noise included, obeys the refractory period.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "camera/event.h"

namespace yelan::camera::sim {

// Intensities are the renderer's linear "luma-like" DN: white under office light ~255,
// medium light ~60, low light a few DN. Log quantities are natural logs.
struct PixelParams {
  double pos_threshold = 0.2;     // nominal ON contrast threshold (log units)
  double neg_threshold = 0.2;     // nominal OFF contrast threshold (log units)
  double sigma_threshold = 0.03;  // per-pixel mismatch: thresholds ~ N(nominal, sigma), >= 0.01
  // Photoreceptor 3 dB cutoff at intensity 255; it scales as (I + cutoff_floor_dn) /
  // (255 + cutoff_floor_dn), so dark pixels are slow but never frozen. 0 = no low-pass.
  double cutoff_hz = 300;
  double cutoff_floor_dn = 20;
  double refractory_s = 0.0005;   // after an event, crossings within this time are dropped
  double leak_rate_hz = 0.1;      // mean ON leak events per pixel per second
  double leak_rate_cov_decades = 0.1;  // per-pixel leak rate spread (log-normal, mean kept)
  double shot_noise_rate_hz = 1.0;     // noise events per pixel per second at intensity 0
  double shot_noise_bright_factor = 0.25;  // shot rate at intensity >= 255, relative to dark
  double hot_pixel_fraction = 1e-4;   // fraction of pixels that are hot (fixed per seed)
  double hot_pixel_rate_hz = 50;      // ON events per second from each hot pixel
  double lin_log_knee = 20;           // below this DN the response is linear (v2e: 20)
};

// Named settings. `clean`: ideal pixel (equal thresholds, no noise, no low-pass, no
// refractory). `davis346`: the defaults above. `noisy`: v2e's "noisy" model (slow
// photoreceptor, wider mismatch, more shot noise, long refractory).
PixelParams pixel_params_clean();
PixelParams pixel_params_davis346();
PixelParams pixel_params_noisy();

// Scalar reference formulas (the model evaluates the same ones in vector form).
// lin-log: I * ln(knee) / knee for I <= knee, ln(I) above; continuous at the knee.
double lin_log(double intensity, double knee);
// Fraction of the way a first-order low-pass moves towards its input over dt seconds:
// 1 - exp(-dt * 2 pi * cutoff(I)), cutoff(I) = cutoff_hz * (I + floor) / (255 + floor).
double lowpass_alpha(double intensity, double dt_s, const PixelParams& params);
// Shot-noise events per second of one pixel with nominal thresholds at this intensity:
// linear from shot_noise_rate_hz at 0 to shot_noise_rate_hz * bright_factor at >= 255.
double shot_noise_rate(double intensity, const PixelParams& params);

struct PixelStats {
  std::uint64_t signal = 0;    // threshold crossings emitted (brightness change and leak)
  std::uint64_t shot = 0;      // shot-noise events emitted
  std::uint64_t hot = 0;       // hot-pixel events emitted
  std::uint64_t refractory_dropped = 0;  // events of any kind dropped by the refractory period
};

class PixelModel {
 public:
  // Throws std::invalid_argument on a size outside 1..65536 or a parameter out of range.
  PixelModel(int width, int height, const PixelParams& params, std::uint64_t seed);

  // Starts from this frame (width*height, row-major) at time t_s: filtered state equals the
  // input, no events. Leak phases and noise clocks are redrawn; thresholds and hot pixels
  // are the sensor's and stay. Must be called before step().
  void reset(const float* intensity, double t_s);

  // Advances from t0_s to t1_s (> t0_s) with the intensity `intensity` reached at t1_s, the
  // input varying linearly in between. Appends the events with t0 < t <= t1 (microseconds,
  // rounded) to `out`, sorted by t, then y, then x. Non-finite or negative intensities
  // count as 0; intensities are capped at 1e9.
  void step(const float* intensity, double t0_s, double t1_s, std::vector<Event>& out);

  // Largest |lin-log(next) - filtered state| over all pixels: a bound on how far any pixel
  // could move in a step to `next`, so the sampler can shorten steps (ESIM's adaptive rule).
  double max_log_change(const float* next) const;

  int width() const { return width_; }
  int height() const { return height_; }
  const PixelParams& params() const { return params_; }
  const PixelStats& stats() const { return stats_; }
  float filtered_log(int x, int y) const { return lp_[index(x, y)]; }
  // Filtered log minus memorised reference: events fire when it reaches +theta_on/-theta_off.
  float log_minus_reference(int x, int y) const { return diff_[index(x, y)]; }
  float threshold_on(int x, int y) const { return thr_on_[index(x, y)]; }
  float threshold_off(int x, int y) const { return thr_off_[index(x, y)]; }
  bool is_hot(int x, int y) const { return hot_[index(x, y)] != 0; }
  std::size_t hot_pixel_count() const { return hot_x_.size(); }

 private:
  struct RowStats {
    std::uint64_t signal = 0, shot = 0, hot = 0, dropped = 0;
  };
  std::size_t index(int x, int y) const { return std::size_t(y) * width_ + x; }
  struct StepSpan {
    double t0_s, dt_s, t1_s;
    std::int64_t lo_us, hi_us;  // event times are clamped into [lo_us, hi_us]
    double base_shift_s;        // shot clocks move back by this much (time_base_ moved)
  };
  // lin-log of n sanitised intensities: clamped copies into `clamped`, logs into `log`.
  void lin_log_chunk(const float* in, int n, float* clamped, float* log) const;
  double noise_scale(std::size_t i) const;
  double draw_wait(std::uint64_t stream, std::size_t pixel, std::uint32_t count,
                   double rate) const;
  void step_row(int y, const float* in, const StepSpan& span, std::vector<Event>& buf,
                RowStats& st);
  void pixel_events(int x, int y, float delta, float intensity, const StepSpan& span,
                    std::vector<Event>& buf, RowStats& st);
  void merge_rows(std::int64_t t0_us, std::int64_t t1_us, std::vector<Event>& out);

  int width_, height_;
  PixelParams params_;
  std::uint64_t seed_;
  std::uint64_t epoch_ = 0;  // number of resets: keys the per-reset draws
  bool ready_ = false;
  float lin_slope_;          // ln(knee) / knee
  // Per pixel (row-major).
  std::vector<float> lp_;       // low-passed lin-log intensity
  std::vector<float> diff_;     // lp - memorised reference
  std::vector<float> thr_on_, thr_off_;
  std::vector<float> leak_;     // reference drift, log units per second
  // Shot noise by thinning: each pixel has a clock of candidate events at its dark rate;
  // a candidate is kept with probability shot_noise_rate(I) / shot_noise_rate(0). The
  // clock is float seconds after time_base_, which moves up every 64 s to stay precise.
  std::vector<float> next_shot_;
  double time_base_ = 0;
  std::vector<std::uint32_t> shot_count_;  // candidates drawn so far: the RNG counter
  std::vector<double> hot_next_;           // per hot pixel (as hot_x_): next event, seconds
  std::vector<std::uint32_t> hot_count_;
  std::vector<double> last_event_s_;        // for the refractory period
  std::vector<std::uint8_t> hot_;
  // Hot pixels by row: row y owns hot_x_[hot_row_begin_[y] .. hot_row_begin_[y+1]).
  std::vector<int> hot_row_begin_;
  std::vector<std::uint16_t> hot_x_;
  // Step scratch, kept between steps so steady-state stepping does not allocate.
  std::vector<std::vector<Event>> row_events_;
  std::vector<RowStats> row_stats_;
  std::vector<std::uint32_t> histogram_;
  std::vector<Event> merged_;
  PixelStats stats_;
  void (*vlog_)(const float*, float*, std::size_t);
  void (*vexp_)(const float*, float*, std::size_t);
};

}  // namespace yelan::camera::sim
