#include "engine/losses.h"

#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "kernels/heatmap.h"

namespace yelan {

using layers::Act;

void target_gaussian(float mu_w, float mu_h, int h, int w, float sigma_px, float* out) {
  // Normalised coordinates span 2 units over n pixels: sigma in them is 2 sigma_px / n.
  const double sw = 2.0 * sigma_px / w, sh = 2.0 * sigma_px / h;
  std::vector<double> gw(w), gh(h);
  for (int c = 0; c < w; ++c) {
    const double d = kernels::dsnt_coordinate(c, w) - mu_w;
    gw[c] = std::exp(-0.5 * d * d / (sw * sw));
  }
  for (int r = 0; r < h; ++r) {
    const double d = kernels::dsnt_coordinate(r, h) - mu_h;
    gh[r] = std::exp(-0.5 * d * d / (sh * sh));
  }
  double sum = 0;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) sum += gh[r] * gw[c];
  sum += 1e-24;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) out[r * w + c] = float(gh[r] * gw[c] / sum);
}

namespace {

constexpr double kEps = 1e-24;

// JS(p, q) over one map (lane `lane` of image n of a blocked Act) and its gradient in p,
// scaled by `scale`, added into dp.
double js_map(const Act& p, int n, int lane, const float* q, double scale, const Act& dp) {
  const std::size_t P = p.pixels();
  const float* base = p.data + (std::size_t(n) * p.cb() + lane / 16) * P * 16 + lane % 16;
  float* g = dp.data + (std::size_t(n) * dp.cb() + lane / 16) * P * 16 + lane % 16;
  double js = 0;
  for (std::size_t i = 0; i < P; ++i) {
    const double a = base[i * 16], b = q[i], m = 0.5 * (a + b);
    const double lm = std::log(m + kEps), la = std::log(a + kEps), lb = std::log(b + kEps);
    js += 0.5 * a * (la - lm) + 0.5 * b * (lb - lm);
    g[i * 16] += float(scale * 0.5 * (la - lm + a / (a + kEps) - m / (m + kEps)));
  }
  return js;
}

}  // namespace

HpeLoss hpe_loss(const PoseNet& net, int stages, const float* target_in, const float* valid_in,
                 std::vector<PoseNet::StageGrads>& dheat, std::vector<layers::Floats>& store, int swap_group) {
  HpeLoss out;
  const Act& ref = net.heatmap(0, 0);
  const int n = ref.n, J = ref.c, h = ref.h, w = ref.w;
  const float *target = target_in, *valid = valid_in;
  std::vector<float> swapped_target, swapped_valid;
  if (swap_group > 0) {
    if (J != 13) throw std::invalid_argument("hpe loss: trading left and right needs SPEC's 13 joints, not " + std::to_string(J));
    std::vector<float> last(std::size_t(n) * J * 3);
    net.stage_joints(stages - 1, last.data());
    swapped_target.assign(target_in, target_in + std::size_t(n) * J * 3);
    swapped_valid.assign(valid_in, valid_in + std::size_t(n) * J);
    auto dist = [&](std::size_t k_pred, std::size_t k_tgt) {
      double s = 0;
      for (int c = 0; c < 3; ++c) s += double(last[k_pred * 3 + c] - target_in[k_tgt * 3 + c]) * (last[k_pred * 3 + c] - target_in[k_tgt * 3 + c]);
      return std::sqrt(s);
    };
    for (int g0 = 0; g0 < n; g0 += swap_group) {
      const int g1 = std::min(n, g0 + swap_group);
      double as_is = 0, traded = 0;
      for (int i = g0; i < g1; ++i)
        for (int j = 0; j < J; ++j) {
          const std::size_t k = std::size_t(i) * J + j, m = std::size_t(i) * J + mirror_joint(j);
          if (valid_in[k] != 0.f) as_is += dist(k, k);
          if (valid_in[m] != 0.f) traded += dist(k, m);
        }
      ++out.groups;
      if (!(traded < as_is)) continue;
      ++out.swapped;
      for (int i = g0; i < g1; ++i)
        for (int j = 0; j < J; ++j) {
          const std::size_t k = std::size_t(i) * J + j, m = std::size_t(i) * J + mirror_joint(j);
          for (int c = 0; c < 3; ++c) swapped_target[k * 3 + c] = target_in[m * 3 + c];
          swapped_valid[k] = valid_in[m];
        }
    }
    target = swapped_target.data();
    valid = swapped_valid.data();
  }
  double count = 0;
  for (int i = 0; i < n * J; ++i) count += valid[i];
  const double denom = std::max(count, 1.0) * stages;  // masked mean, then the stage mean
  dheat.assign(stages, {});
  store.resize(std::size_t(stages) * 4);
  std::vector<float> joints(std::size_t(n) * J * 3), dj(joints.size()), gauss(std::size_t(h) * w);
  for (int t = 0; t < stages; ++t) {
    const Act* depth = net.depth_map(t);
    for (int p = 0; p < (depth ? 4 : 3); ++p) {
      const Act& hm = p < 3 ? net.heatmap(t, p) : *depth;
      layers::Floats& f = store[t * 4 + p];
      if (f.size() != hm.floats()) f = layers::Floats(hm.floats());
      f.zero();
      dheat[t][p] = Act{f.data(), hm.n, hm.c, hm.h, hm.w};
    }
    net.stage_joints(t, joints.data());
    double stage = 0, euclid = 0;
    std::fill(dj.begin(), dj.end(), 0.f);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < J; ++j) {
        const std::size_t k = std::size_t(i) * J + j;
        if (valid[k] == 0.f) continue;
        const float* tg = target + k * 3;
        const float* pr = joints.data() + k * 3;
        const double dx = pr[0] - tg[0], dy = pr[1] - tg[1], dz = pr[2] - tg[2];
        const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
        euclid += d;
        if (d > 0) {
          dj[k * 3 + 0] = float(dx / d / denom);
          dj[k * 3 + 1] = float(dy / d / denom);
          dj[k * 3 + 2] = float(dz / d / denom);
        }
        // xy: (x, y); zy: width z, height y; xz: width x, height z
        const float mu[3][2] = {{tg[0], tg[1]}, {tg[2], tg[1]}, {tg[0], tg[2]}};
        for (int p = 0; p < 3; ++p) {
          target_gaussian(mu[p][0], mu[p][1], h, w, 1.f, gauss.data());
          stage += js_map(net.heatmap(t, p), i, j, gauss.data(), 1.0 / denom, dheat[t][p]);
        }
      }
    // the distance's gradient reaches the maps through DSNT
    std::vector<layers::Floats> tmp(3);
    std::array<Act, 3> g;
    for (int p = 0; p < 3; ++p) {
      tmp[p] = layers::Floats(dheat[t][p].floats());
      g[p] = Act{tmp[p].data(), dheat[t][p].n, dheat[t][p].c, dheat[t][p].h, dheat[t][p].w};
    }
    // with depth maps, z's gradient reaches them and the xy map under them, not zy and xz
    layers::stage_joints_backward(dj.data(), net.heatmap(t, 0), depth, g[0], g[1], g[2], depth ? &dheat[t][3] : nullptr);
    for (int p = 0; p < 3; ++p) layers::accumulate(g[p], dheat[t][p]);
    stage += euclid;
    out.per_stage.push_back(stage / std::max(count, 1.0));
    out.euclid.push_back(euclid / std::max(count, 1.0));
    out.total += stage / denom;
  }
  return out;
}

MaskLoss mask_loss(const MaskNet& net, const Act& labels, const Act& dmasks, std::vector<float>& dscores,
                   const std::vector<float>& sample_weights, double dice_weight, int focus) {
  const Act& m = net.masks();
  const int n = m.n, N = m.c;
  const std::size_t P = m.pixels();
  if (!sample_weights.empty() && sample_weights.size() != std::size_t(n))
    throw std::invalid_argument("mask loss: " + std::to_string(sample_weights.size()) + " sample weights for " +
                                std::to_string(n) + " samples");
  auto weight = [&](int i) { return sample_weights.empty() ? 1.0 : double(sample_weights[std::size_t(i)]); };
  double total_w = 0;
  for (int i = 0; i < n; ++i) total_w += weight(i);
  if (!(total_w > 0)) throw std::invalid_argument("mask loss: the sample weights sum to " + std::to_string(total_w));
  if (!(dice_weight >= 0)) throw std::invalid_argument("mask loss: the Dice weight must be >= 0");
  if (focus < 0 || focus >= N)
    throw std::invalid_argument("mask loss: focus " + std::to_string(focus) + " outside 0.." + std::to_string(N - 1) +
                                " (the future masks of " + std::to_string(N) + ")");
  MaskLoss out;
  std::memset(dmasks.data, 0, dmasks.floats() * sizeof(float));
  const double n_first = total_w * P, n_all = total_w * N * P;
  std::vector<double> score_gt(std::size_t(n) * N, 0.0);
  // The Dice term's sums over the current mask, per sample: sum(p y), sum p, sum y.
  std::vector<std::array<double, 3>> dice_sums(std::size_t(n), {0.0, 0.0, 0.0});
  for (int i = 0; i < n; ++i) {
    const double wi = weight(i);
    for (int c = 0; c < N; ++c) {
      const std::size_t off = (std::size_t(i) * m.cb() + c / 16) * P * 16 + c % 16;
      double abs_sum = 0;
      for (std::size_t p = 0; p < P; ++p) {
        const double x = m.data[off + p * 16], y = labels.data[off + p * 16];
        const double l = wi * (std::max(x, 0.0) - x * y + std::log1p(std::exp(-std::abs(x))));
        const double s = 1.0 / (1.0 + std::exp(-x));
        out.bce_all += l / n_all;
        double g = wi * (s - y) / n_all;
        if (c == 0) {
          out.bce_first += l / n_first;
          g += wi * (s - y) / n_first;
          auto& d = dice_sums[std::size_t(i)];
          d[0] += s * y;
          d[1] += s;
          d[2] += y;
        } else if (c <= focus) {
          out.bce_focus += l / n_first;
          g += wi * (s - y) / n_first;
        }
        dmasks.data[off + p * 16] = float(g);
        abs_sum += std::abs(s - y);
      }
      score_gt[std::size_t(i) * N + c] = 1.0 - abs_sum / double(P);
    }
  }
  dscores.assign(std::size_t(n) * N, 0.f);
  const auto& s = net.scores();
  const double n_scores = total_w * N;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const double wi = weight(int(k / std::size_t(N)));
    const double d = s[k] - score_gt[k];
    out.score_mse += wi * d * d / n_scores;
    dscores[k] = float(2.0 * wi * d / n_scores);
  }
  for (int i = 0; i < n; ++i) {
    const auto& d = dice_sums[std::size_t(i)];
    const double num = 2 * d[0] + 1, den = d[1] + d[2] + 1, share = weight(i) / total_w;
    out.dice += share * (1 - num / den);
    if (dice_weight == 0) continue;
    const std::size_t off = std::size_t(i) * m.cb() * P * 16;  // channel 0
    for (std::size_t p = 0; p < P; ++p) {
      const double s = 1.0 / (1.0 + std::exp(-double(m.data[off + p * 16]))), y = labels.data[off + p * 16];
      const double d_s = -(2 * y * den - num) / (den * den);
      dmasks.data[off + p * 16] += float(dice_weight * share * d_s * s * (1 - s));
    }
  }
  out.total = out.bce_first + out.bce_focus + out.bce_all + out.score_mse + dice_weight * out.dice;
  return out;
}

std::vector<float> nobody_weights(const Act& labels, float nobody) {
  std::vector<float> w(std::size_t(labels.n), 1.f);
  const std::size_t P = labels.pixels();
  for (int i = 0; i < labels.n; ++i) {
    const float* first = labels.data + std::size_t(i) * labels.cb() * P * 16;  // channel 0
    bool anyone = false;
    for (std::size_t p = 0; p < P && !anyone; ++p) anyone = first[p * 16] > 0.5f;
    if (!anyone) w[std::size_t(i)] = nobody;
  }
  return w;
}

}  // namespace yelan
