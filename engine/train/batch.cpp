#include "engine/train/batch.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "engine/input.h"
#include "layers/simple.h"

namespace yelan::train {

MaskReuse draw_mask_reuse(camera::sim::Rng& r, int max_period) {
  if (max_period < 1) throw std::invalid_argument("mask reuse: the longest period must be >= 1 frame");
  MaskReuse m;
  m.period = 1 + r.below(max_period);
  m.phase = r.below(m.period);
  return m;
}

BatchBuilder::BatchBuilder(const ModelConfig& cfg, int windows, MaskSource source, int lead)
    : cfg_(cfg), windows_(windows), lead_(lead), source_(source != MaskSource::none && !cfg.masked_input ? MaskSource::unmasked : source) {
  if (lead < 0) throw std::invalid_argument("a window's lead must be >= 0 frames");
  if (cfg.representation == "tore" && cfg.channels != 6)
    throw std::invalid_argument("config " + cfg.name + ": " + std::to_string(cfg.channels) +
                                " input channels, but TORE with K = 3 gives 6");
  outside_ = cfg.outside_input && (source_ == MaskSource::truth || source_ == MaskSource::net);
  const int n = windows * cfg.window, h = cfg.height(), w = cfg.width();
  b_.input.resize(n, outside_ ? cfg.pose_channels() : cfg.channels, h, w);
  if (source_ == MaskSource::none) b_.labels.resize(n, cfg.n_masks, h, w);
  b_.target.assign(std::size_t(n) * kJoints * 3, 0.f);
  b_.valid.assign(std::size_t(n) * kJoints, 0.f);
  b_.valid_u8.assign(std::size_t(n) * kJoints, 0);
  b_.truth_mm.resize(std::size_t(n));
  b_.z_ref.resize(std::size_t(n));
  b_.frames = n;
  if (source_ == MaskSource::net) one_.resize(cfg.window, cfg.channels, h, w);
}

const std::vector<float>& input_planes(const ModelConfig& cfg, const camera::sim::SimFrame& f, std::vector<float>& scratch) {
  if (cfg.representation == "tore") return f.tore;
  if (f.counts.empty()) throw std::logic_error("counts input, but the simulator stream did not count events");
  scratch.resize(f.counts.size());
  for (std::size_t i = 0; i < scratch.size(); ++i) scratch[i] = std::log1p(f.counts[i]);
  return scratch;
}

namespace {

// Fraction of human pixels in each d x d cell.
std::vector<float> mask_cells(const std::vector<std::uint8_t>& m, int sensor_w, int d, int H, int W) {
  std::vector<float> out(std::size_t(H) * W);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      int s = 0;
      for (int dy = 0; dy < d; ++dy)
        for (int dx = 0; dx < d; ++dx) s += m[std::size_t(y * d + dy) * sensor_w + x * d + dx] != 0;
      out[std::size_t(y) * W + x] = float(s) / float(d * d);
    }
  return out;
}

}  // namespace

Pose13 predicted_pose_mm(const Batch& b, const std::vector<float>& joints_norm, int f) {
  Pose13 pred;
  for (int j = 0; j < kJoints; ++j) {
    const float* q = &joints_norm[(std::size_t(f) * kJoints + j) * 3];
    pred[j] = denormalise_joint({q[0], q[1], q[2]}, b.k, b.z_ref[std::size_t(f)]);
  }
  return pred;
}

std::array<std::uint8_t, kJoints> valid_joints(const Batch& b, int f) {
  std::array<std::uint8_t, kJoints> valid;
  std::copy_n(&b.valid_u8[std::size_t(f) * kJoints], kJoints, valid.begin());
  return valid;
}

void BatchBuilder::add(const camera::sim::SimWindow& w, MaskNet& mask_net, camera::sim::Rng* occ, const Similarity* warp,
                       bool flip, const MaskReuse* reuse) {
  if (used_ >= windows_) throw std::logic_error("batch is full");
  const int S = cfg_.window, d = cfg_.downscale, H = cfg_.height(), W = cfg_.width(), L = lead_;
  if (reuse && source_ == MaskSource::net &&
      (reuse->period < 1 || reuse->period > cfg_.n_masks || reuse->phase < 0 || reuse->phase >= reuse->period || reuse->phase > L))
    throw std::invalid_argument("mask reuse every " + std::to_string(reuse->period) + " frames at phase " +
                                std::to_string(reuse->phase) + ": needs 1 <= period <= " + std::to_string(cfg_.n_masks) +
                                " masks, phase < period and <= the window's lead of " + std::to_string(L) + " frames");
  const bool fresh = source_ == MaskSource::net && !reuse;
  const int sw = w.camera.width, sh = w.camera.height;
  if (sw != cfg_.sensor_width || sh != cfg_.sensor_height)
    throw std::invalid_argument("simulated sensor is " + std::to_string(sw) + "x" + std::to_string(sh) + ", the model expects " +
                                std::to_string(cfg_.sensor_width) + "x" + std::to_string(cfg_.sensor_height));
  const int need = L + S + (source_ == MaskSource::none ? cfg_.n_masks - 1 : 0);
  if (int(w.frames.size()) < need) throw std::invalid_argument("window too short for the model");
  b_.k = {w.camera.fx, w.camera.fy, w.camera.cx, w.camera.cy, sw, sh};
  const layers::Act& in = b_.input.act;
  const layers::Act tore_in{in.data, in.n, cfg_.channels, in.h, in.w};  // the TORE's channels (one block either way)
  const auto mask_input = [&](int n, const std::vector<float>& keep) {
    input::mask_stage2_input(in, n, keep, outside_, cfg_.crop_margin);
  };
  for (int t = 0; t < S; ++t) {
    const int n = used_ * S + t;
    const auto& f = w.frames[std::size_t(L + t)];
    const std::vector<float>& planes = input_planes(cfg_, f, planes_);
    input::downscale_tore(planes, sh, sw, d, tore_in, n);
    if (fresh) input::downscale_tore(planes, sh, sw, d, one_.act, t);
    if (source_ == MaskSource::truth) {
      auto cells = mask_cells(f.mask, sw, d, H, W);
      for (float& c : cells) c = c > 0 ? 1.f : 0.f;  // any human pixel keeps the cell
      input::grow_mask(cells, H, W, cfg_.mask_grow);
      mask_input(n, cells);
    }
    if (occ && occ->uniform() < 0.5) {
      const int rects = 1 + occ->below(2);
      for (int r = 0; r < rects; ++r) {
        const int rw = int(occ->uniform(10, 80)) / d + 1, rh = int(occ->uniform(10, 80)) / d + 1;
        const int x0 = occ->below(W), y0 = occ->below(H);
        std::vector<float> keep(std::size_t(H) * W, 1.f);
        for (int y = y0; y < std::min(H, y0 + rh); ++y)
          for (int x = x0; x < std::min(W, x0 + rw); ++x) keep[std::size_t(y) * W + x] = 0.f;
        input::apply_mask(in, n, keep);
      }
    }
    // Targets: the joints normalised with the true head depth (both warped with the input).
    const double zr0 = f.joints_mm[0].z();
    const double zr = warp ? zr0 / warp->scale : zr0;
    b_.z_ref[std::size_t(n)] = zr;
    Pose13 ps;
    std::array<bool, kJoints> oks;
    for (int j = 0; j < kJoints; ++j) {
      auto& p = ps[std::size_t(j)];
      p = {f.joints_mm[j].x(), f.joints_mm[j].y(), f.joints_mm[j].z()};
      bool ok = f.valid[j] && p[2] > 1 && zr0 > 1;
      if (warp && ok) {
        p = warp_joint(*warp, p, b_.k, zr0);
        const double u = b_.k.fx * p[0] / p[2] + b_.k.cx, v = b_.k.fy * p[1] / p[2] + b_.k.cy;
        ok = p[2] > 1 && u >= 0 && u < sw && v >= 0 && v < sh;  // still in the picture
      }
      if (flip && p[2] > 1) p = flip_joint(p, b_.k, W, d);
      oks[std::size_t(j)] = ok;
    }
    if (flip) {
      ps = swap_left_right(ps);
      oks = swap_left_right(oks);
    }
    for (int j = 0; j < kJoints; ++j) {
      const auto& p = ps[std::size_t(j)];
      const bool ok = oks[std::size_t(j)];
      b_.truth_mm[std::size_t(n)][j] = p;
      const auto q = ok ? normalise_joint(p, b_.k, zr) : std::array<double, 3>{0, 0, 0};
      for (int c = 0; c < 3; ++c) b_.target[(std::size_t(n) * kJoints + j) * 3 + c] = float(q[c]);
      b_.valid[std::size_t(n) * kJoints + j] = ok ? 1.f : 0.f;
      b_.valid_u8[std::size_t(n) * kJoints + j] = ok;
    }
    if (source_ == MaskSource::none) {
      const layers::Act& lab = b_.labels.act;
      for (int k = 0; k < cfg_.n_masks; ++k) {
        const auto cells = mask_cells(w.frames[std::size_t(L + t + k)].mask, sw, d, H, W);
        float* p = lab.data + (std::size_t(n) * lab.cb() + k / 16) * lab.pixels() * 16 + k % 16;
        for (std::size_t i = 0; i < lab.pixels(); ++i) p[i * 16] = cells[i] >= 0.5f ? 1.f : 0.f;
      }
    }
  }
  if (fresh) {
    layers::NoGrad no_grad;
    mask_net.forward(one_.act);
    std::vector<float> keep;
    for (int t = 0; t < S; ++t) {
      input::mask_cut(mask_net.masks(), t, 0, keep, float(cfg_.mask_cut));  // channel 0: the current mask
      input::grow_mask(keep, H, W, cfg_.mask_grow);
      mask_input(used_ * S + t, keep);
    }
  } else if (source_ == MaskSource::net) {
    // Stage 1 at frames -phase, -phase + period, ... (at most S runs: one_ holds them).
    const int P = reuse->period, k = reuse->phase;
    int runs = 0;
    for (int r = -k; r < S; r += P)
      input::downscale_tore(input_planes(cfg_, w.frames[std::size_t(L + r)], planes_), sh, sw, d, one_.act, runs++);
    layers::NoGrad no_grad;
    mask_net.forward({one_.act.data, runs, one_.act.c, one_.act.h, one_.act.w});
    std::vector<float> keep;
    for (int t = 0; t < S; ++t) {
      const int age = (t + k) % P;  // as yelan run: a reused future mask at run.mask_cut_reused
      input::mask_cut(mask_net.masks(), (t + k) / P, age, keep, float(age ? cfg_.reused_mask_cut() : cfg_.mask_cut));
      input::grow_mask(keep, H, W, cfg_.mask_grow);
      mask_input(used_ * S + t, keep);
    }
  }
  // Last, so the input is warped whole, masks and occluders with it; the mask stage's
  // labels move with it (resampled, then binary again at half a cell).
  if (warp)
    for (int t = 0; t < S; ++t) {
      const int n = used_ * S + t;
      warp_frame(in, n, *warp, d, sw, sh);
      if (source_ != MaskSource::none) continue;
      const layers::Act& lab = b_.labels.act;
      warp_frame(lab, n, *warp, d, sw, sh);
      float* p = lab.data + std::size_t(n) * lab.cb() * lab.pixels() * 16;
      for (std::size_t i = 0; i < std::size_t(lab.cb()) * lab.pixels() * 16; ++i) p[i] = p[i] >= 0.5f ? 1.f : 0.f;
    }
  if (flip)
    for (int t = 0; t < S; ++t) {
      layers::flip_frame(in, used_ * S + t);
      if (source_ == MaskSource::none) layers::flip_frame(b_.labels.act, used_ * S + t);
    }
  ++used_;
}

}  // namespace yelan::train
