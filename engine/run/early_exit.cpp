#include "engine/run/early_exit.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "engine/run/pipeline.h"
#include "engine/run/true_masks.h"
#include "engine/train/mask_overlap.h"

namespace yelan::run {

namespace {

// Ticks on the recording's mask clock at rate_hz, early exit at beta.
RunOptions options_for(const TrueMasks& tm, double rate_hz, double beta) {
  RunOptions opt;
  opt.rate_hz = rate_hz;
  opt.beta = beta;
  opt.tick_origin_us = tm.info.mask_t.empty() ? 0 : tm.info.mask_t[0];
  return opt;
}

}  // namespace

std::vector<BetaPoint> sweep_beta(const std::string& weights, const std::vector<std::string>& recordings,
                                  const std::vector<double>& betas, double rate_hz, double seconds, double skip_s,
                                  std::ostream& progress, std::optional<double> mask_cut) {
  std::vector<BetaPoint> out;
  for (const double beta : betas) {
    BetaPoint pt;
    pt.beta = beta;
    train::MaskOverlap overlap;
    std::uint64_t mask_runs = 0, with_events = 0;
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, sad = 0;
    for (const std::string& path : recordings) {
      const TrueMasks tm(path, seconds, skip_s);
      if (!tm.info.dancer) continue;
      const int W = tm.info.camera.width;
      RunOptions opt = options_for(tm, rate_hz, beta);
      opt.mask_cut = mask_cut;
      opt.cut_every_mask = true;
      PosePipeline pipe(weights, W, tm.info.camera.height, opt);
      const int d = pipe.mask_downscale(), mw = W / d, mh = tm.info.camera.height / d;
      const auto score = [&](const Pose& p) {
        if (p.t_us < tm.t0 || !pipe.masks_are_for(p)) return;
        const auto here = tm.index_at(p.t_us);
        if (!here) return;
        const std::uint8_t* truth = tm.mask(*here);
        const std::vector<float>& pm = pipe.last_stage1_mask();
        if (pm.size() != std::size_t(mw) * mh) return;
        // Stage 1 ran here: each future mask's score against its true quality.
        if (p.mask_ran) {
          const auto& masks = pipe.stored_masks();
          const auto& scores = pipe.stored_scores();
          for (std::size_t k = 0; k < masks.size() && k < scores.size() && *here + k < tm.m1; ++k) {
            const std::uint8_t* fm = tm.mask(*here + k);
            double wrong = 0;
            for (int y = 0; y < mh; ++y)
              for (int x = 0; x < mw; ++x)
                wrong += (masks[k][std::size_t(y) * mw + x] > 0) != (fm[std::size_t(y * d + d / 2) * W + x * d + d / 2] != 0);
            const double q = 1 - wrong / double(mw * mh), sc = scores[k];
            sx += sc, sy += q, sxx += sc * sc, syy += q * q, sxy += sc * q, sad += std::abs(sc - q);
            ++pt.scored_masks;
          }
        }
        train::add_mask_overlap(overlap, truth, W, pm.data(), mh, mw, d);
        ++pt.ticks;
      };
      run_file(pipe, path, tm.end, score);
      mask_runs += pipe.stats().mask_runs;
      with_events += pipe.stats().ticks - pipe.stats().stale;
    }
    pt.iou = overlap.iou();
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

std::vector<double> sweep_mask_cuts(const std::string& weights, const std::vector<std::string>& recordings,
                                    const std::vector<double>& cuts, double rate_hz, double seconds, double skip_s,
                                    std::ostream& progress) {
  std::vector<float> logit_cuts;
  for (const double c : cuts) {
    if (!(c > 0 && c < 1)) throw std::invalid_argument("sweep_mask_cuts: a cut must lie in (0, 1)");
    logit_cuts.push_back(float(std::log(c / (1 - c))));
  }
  std::vector<double> inter(cuts.size(), 0), uni(cuts.size(), 0);
  std::uint64_t ticks = 0;
  for (const std::string& path : recordings) {
    const TrueMasks tm(path, seconds, skip_s);
    if (!tm.info.dancer) continue;
    const int W = tm.info.camera.width;
    // Stage 1 on every tick: the mask in use is always this tick's.
    PosePipeline pipe(weights, W, tm.info.camera.height, options_for(tm, rate_hz, 1.01));
    const int d = pipe.mask_downscale(), mw = W / d, mh = tm.info.camera.height / d;
    run_file(pipe, path, tm.end, [&](const Pose& p) {
      if (p.t_us < tm.t0 || !p.mask_ran || !pipe.masks_are_for(p)) return;
      const auto here = tm.index_at(p.t_us);
      if (!here) return;
      const std::uint8_t* truth = tm.mask(*here);
      const layers::Act& lg = pipe.stage1_logits();
      if (lg.w != mw || lg.h != mh) return;
      for (int y = 0; y < mh; ++y)
        for (int x = 0; x < mw; ++x) {
          const float v = lg.data[(std::size_t(y) * mw + x) * 16];  // channel 0 of block 0 of frame 0
          const bool tr = truth[std::size_t(y * d + d / 2) * W + x * d + d / 2] != 0;
          for (std::size_t k = 0; k < cuts.size(); ++k) {
            const bool pr = v > logit_cuts[k];
            inter[k] += pr && tr;
            uni[k] += pr || tr;
          }
        }
      ++ticks;
    });
  }
  std::vector<double> iou(cuts.size());
  progress << "  stage 1 on every tick, " << ticks << " ticks: IoU";
  for (std::size_t k = 0; k < cuts.size(); ++k) {
    iou[k] = uni[k] > 0 ? inter[k] / uni[k] : 0;
    progress << " " << cuts[k] << ": " << iou[k];
  }
  progress << "\n";
  return iou;
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
