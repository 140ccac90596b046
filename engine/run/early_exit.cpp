#include "engine/run/early_exit.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "camera/sim/recording_windows.h"
#include "engine/run/pipeline.h"

namespace yelan::run {

std::vector<BetaPoint> sweep_beta(const std::string& weights, const std::vector<std::string>& recordings,
                                  const std::vector<double>& betas, double rate_hz, double seconds, double skip_s,
                                  std::ostream& progress, std::optional<double> mask_cut) {
  std::vector<BetaPoint> out;
  for (const double beta : betas) {
    BetaPoint pt;
    pt.beta = beta;
    double inter = 0, uni = 0;
    std::uint64_t mask_runs = 0, with_events = 0;
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, sad = 0;
    for (const std::string& path : recordings) {
      const camera::sim::RecordingInfo info = camera::sim::read_recording_info(path);
      if (!info.dancer) continue;
      const int W = info.camera.width, H = info.camera.height;
      const std::int64_t t0 = info.first_event_us + std::llround(skip_s * 1e6);
      const std::int64_t end = info.first_event_us + std::llround((skip_s + seconds) * 1e6);
      const std::size_t m0 = std::size_t(std::lower_bound(info.mask_t.begin(), info.mask_t.end(), t0) - info.mask_t.begin());
      const std::size_t m1 = std::size_t(std::upper_bound(info.mask_t.begin(), info.mask_t.end(), end) - info.mask_t.begin());
      const std::vector<std::uint8_t> truth = camera::sim::read_recording_masks(path, m0, m1 - m0);
      RunOptions opt;
      opt.rate_hz = rate_hz;
      opt.beta = beta;
      opt.mask_cut = mask_cut;
      opt.tick_origin_us = info.mask_t.empty() ? 0 : info.mask_t[0];
      PosePipeline pipe(weights, W, H, opt);
      const int d = pipe.mask_downscale(), mw = W / d, mh = H / d;
      const auto score = [&](const Pose& p) {
        if (p.t_us < t0 || p.stale) return;
        // The true mask at the tick (ticks sit on the mask times).
        const auto it = std::lower_bound(info.mask_t.begin() + std::ptrdiff_t(m0), info.mask_t.begin() + std::ptrdiff_t(m1), p.t_us);
        if (it == info.mask_t.begin() + std::ptrdiff_t(m1) || std::llabs(*it - p.t_us) > 1000) return;
        const std::uint8_t* tm = &truth[std::size_t(it - info.mask_t.begin() - std::ptrdiff_t(m0)) * std::size_t(W) * H];
        const std::vector<float>& pm = pipe.last_mask();
        if (pm.size() != std::size_t(mw) * mh) return;
        // Stage 1 ran here: each future mask's score against its true quality.
        if (p.mask_ran) {
          const auto& masks = pipe.stored_masks();
          const auto& scores = pipe.stored_scores();
          const std::size_t here = std::size_t(it - info.mask_t.begin());
          for (std::size_t k = 0; k < masks.size() && k < scores.size() && here + k < m1; ++k) {
            const std::uint8_t* fm = &truth[(here + k - m0) * std::size_t(W) * H];
            double wrong = 0;
            for (int y = 0; y < mh; ++y)
              for (int x = 0; x < mw; ++x)
                wrong += (masks[k][std::size_t(y) * mw + x] > 0) != (fm[std::size_t(y * d + d / 2) * W + x * d + d / 2] != 0);
            const double q = 1 - wrong / double(mw * mh), sc = scores[k];
            sx += sc, sy += q, sxx += sc * sc, syy += q * q, sxy += sc * q, sad += std::abs(sc - q);
            ++pt.scored_masks;
          }
        }
        for (int y = 0; y < mh; ++y)
          for (int x = 0; x < mw; ++x) {
            const bool pr = pm[std::size_t(y) * mw + x] > 0;
            const bool tr = tm[std::size_t(y * d + d / 2) * W + x * d + d / 2] != 0;
            inter += pr && tr;
            uni += pr || tr;
          }
        ++pt.ticks;
      };
      run_file(pipe, path, end, score);
      mask_runs += pipe.stats().mask_runs;
      with_events += pipe.stats().ticks - pipe.stats().stale;
    }
    pt.iou = uni > 0 ? inter / uni : 0;
    if (pt.scored_masks > 1) {
      const double n = double(pt.scored_masks);
      const double cov = sxy / n - sx / n * sy / n, vx = sxx / n - sx / n * sx / n, vy = syy / n - sy / n * sy / n;
      pt.score_quality_correlation = vx > 0 && vy > 0 ? cov / std::sqrt(vx * vy) : 0;
      pt.score_quality_mae = sad / n;
    }
    pt.stage1_share = with_events ? double(mask_runs) / double(with_events) : 0;
    progress << "  beta " << beta << ": stage 1 on " << 100 * pt.stage1_share << "% of the ticks, mask IoU " << pt.iou << " ("
             << pt.ticks << " ticks)\n";
    out.push_back(pt);
  }
  return out;
}

BetaPoint choose_beta(const std::vector<BetaPoint>& points, double tolerance) {
  if (points.empty()) throw std::invalid_argument("choose_beta: no points");
  double best = 0;
  for (const auto& p : points) best = std::max(best, p.iou);
  const BetaPoint* pick = nullptr;
  for (const auto& p : points)
    if (p.iou >= best - tolerance &&
        (!pick || p.stage1_share < pick->stage1_share || (p.stage1_share == pick->stage1_share && p.beta > pick->beta)))
      pick = &p;
  return *pick;
}

}  // namespace yelan::run
