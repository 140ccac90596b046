#include "layers/hourglass.h"

#include <cstring>
#include <stdexcept>
#include <vector>

#include "kernels/heatmap.h"

namespace yelan::layers {

namespace {
constexpr std::size_t kSkipFrom = 1, kSkipTo = 7;  // the second down block's output -> the up block's
}

HourglassStage::HourglassStage(int in, int joints, int lo, int hi, int mid_h, int mid_w, bool skip) : skip_(skip) {
  using K = ResidualKind;
  auto add = [&](int a, int b, K k, int oph = 0, int opw = 0) {
    blocks_.push_back(std::make_unique<ResidualBlock>(a, b, k, oph, opw));
  };
  add(in, lo, K::regular);
  add(lo, lo, K::regular);
  add(lo, hi, K::down);
  add(hi, hi, K::regular);
  add(hi, hi, K::regular);
  add(hi, hi, K::regular);
  add(hi, hi, K::regular);
  add(hi, lo, K::up, mid_h % 2 == 0, mid_w % 2 == 0);
  add(lo, lo, K::regular);
  add(lo, joints, K::regular);
}

void HourglassStage::params(const std::string& prefix, ParamList& out) {
  for (std::size_t i = 0; i < blocks_.size(); ++i)
    blocks_[i]->params(prefix + (i < 5 ? "down_layers." : "up_layers.") + std::to_string(i % 5) + ".", out);
}

void HourglassStage::init(std::uint64_t seed) {
  for (std::size_t i = 0; i < blocks_.size(); ++i) blocks_[i]->init(seed * 16 + i);
}
void HourglassStage::set_training(bool on) {
  for (auto& b : blocks_) b->set_training(on);
}
void HourglassStage::weights_changed() {
  for (auto& b : blocks_) b->weights_changed();
}

Act HourglassStage::forward(const Act& x) {
  inputs_.assign(1, x);
  Act a = x;
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    a = blocks_[i]->forward(a);
    if (skip_ && i == kSkipTo) {
      const Act sum = sum_.like(a);
      add_forward(a, inputs_[kSkipFrom + 1], sum);
      a = sum;
    }
    inputs_.push_back(a);
  }
  inputs_.pop_back();  // inputs_[i] is block i's input
  return a;
}

void HourglassStage::backward(const Act& x, const Act& dy, const Act& dx) {
  Act g = dy;
  for (int i = int(blocks_.size()) - 1; i >= 0; --i) {
    const Act& in = inputs_[i];
    const Act d = i == 0 ? dx : (i % 2 ? grad_a_ : grad_b_).like(in);
    blocks_[i]->backward(in, g, d);
    g = d;
    if (skip_ && i == kSkipTo + 1) {  // g: dL/d(the sum), which both addends receive
      const Act keep = dsum_.like(g);
      std::memcpy(keep.data, g.data, g.floats() * sizeof(float));
    }
    if (skip_ && i == kSkipFrom + 1) accumulate(dsum_.act, g);
  }
}

void flat_softmax_forward(const Act& logits, const Act& probs) {
  kernels::heatmap_kernels().softmax_fwd(logits.n * logits.cb(), logits.pixels(), logits.data, probs.data);
  // padding lanes would each become a uniform 1/(h w): keep them zero
  if (probs.c % 16)
    for (int n = 0; n < probs.n; ++n) {
      float* p = probs.data + (std::size_t(n) * probs.cb() + probs.cb() - 1) * probs.pixels() * 16;
      for (std::size_t px = 0; px < probs.pixels(); ++px)
        for (int l = probs.c % 16; l < 16; ++l) p[px * 16 + l] = 0.f;
    }
}

void flat_softmax_backward(const Act& probs, const Act& dprobs, const Act& dlogits) {
  kernels::heatmap_kernels().softmax_bwd(probs.n * probs.cb(), probs.pixels(), probs.data, dprobs.data, dlogits.data);
}

void dsnt_joints_forward(const Act& xy, const Act& zy, const Act& xz, float* joints) {
  const int planes = xy.n * xy.cb(), J = xy.c;
  std::vector<float> a(planes * 32), b(planes * 32), c(planes * 32);
  const auto& k = kernels::heatmap_kernels();
  k.dsnt_fwd(planes, xy.h, xy.w, xy.data, a.data());
  k.dsnt_fwd(planes, zy.h, zy.w, zy.data, b.data());
  k.dsnt_fwd(planes, xz.h, xz.w, xz.data, c.data());
  for (int n = 0; n < xy.n; ++n)
    for (int j = 0; j < J; ++j) {
      const int p = n * xy.cb() + j / 16, l = j % 16;
      float* o = joints + (std::size_t(n) * J + j) * 3;
      o[0] = a[(p * 2 + 0) * 16 + l];
      o[1] = a[(p * 2 + 1) * 16 + l];
      o[2] = 0.5f * (b[(p * 2 + 0) * 16 + l] + c[(p * 2 + 1) * 16 + l]);
    }
}

void dsnt_joints_backward(const float* dj, const Act& dxy, const Act& dzy, const Act& dxz) {
  const int planes = dxy.n * dxy.cb(), J = dxy.c;
  std::vector<float> a(planes * 32, 0.f), b(planes * 32, 0.f), c(planes * 32, 0.f);
  for (int n = 0; n < dxy.n; ++n)
    for (int j = 0; j < J; ++j) {
      const int p = n * dxy.cb() + j / 16, l = j % 16;
      const float* g = dj + (std::size_t(n) * J + j) * 3;
      a[(p * 2 + 0) * 16 + l] = g[0];
      a[(p * 2 + 1) * 16 + l] = g[1];
      b[(p * 2 + 0) * 16 + l] = 0.5f * g[2];
      c[(p * 2 + 1) * 16 + l] = 0.5f * g[2];
    }
  const auto& k = kernels::heatmap_kernels();
  k.dsnt_bwd(planes, dxy.h, dxy.w, a.data(), dxy.data);
  k.dsnt_bwd(planes, dzy.h, dzy.w, b.data(), dzy.data);
  k.dsnt_bwd(planes, dxz.h, dxz.w, c.data(), dxz.data);
}

void expected_depth_forward(const Act& xy, const Act& depth, float* joints) {
  const int J = xy.c;
  const std::size_t P = xy.pixels();
  for (int n = 0; n < xy.n; ++n)
    for (int j = 0; j < J; ++j) {
      const float* p = xy.lane(n, j, 0);
      const float* d = depth.lane(n, j, 0);
      double z = 0;
      for (std::size_t i = 0; i < P; ++i) z += double(p[i * 16]) * d[i * 16];
      joints[(std::size_t(n) * J + j) * 3 + 2] = float(z);
    }
}

void expected_depth_backward(const float* dj, const Act& xy, const Act& depth, const Act& dxy, const Act& ddepth) {
  std::memset(ddepth.data, 0, ddepth.floats() * sizeof(float));
  const int J = xy.c;
  const std::size_t P = xy.pixels();
  for (int n = 0; n < xy.n; ++n)
    for (int j = 0; j < J; ++j) {
      const float g = dj[(std::size_t(n) * J + j) * 3 + 2];
      const float* p = xy.lane(n, j, 0);
      const float* d = depth.lane(n, j, 0);
      float* gp = dxy.lane(n, j, 0);
      float* gd = ddepth.lane(n, j, 0);
      for (std::size_t i = 0; i < P; ++i) {
        gp[i * 16] += g * d[i * 16];
        gd[i * 16] = g * p[i * 16];
      }
    }
}

void stage_joints_forward(const Act& xy, const Act& zy, const Act& xz, const Act* depth, float* joints) {
  dsnt_joints_forward(xy, zy, xz, joints);
  if (depth) expected_depth_forward(xy, *depth, joints);
}

void stage_joints_backward(const float* dj, const Act& xy, const Act* depth, const Act& dxy, const Act& dzy, const Act& dxz,
                           const Act* ddepth) {
  if (!depth) {
    dsnt_joints_backward(dj, dxy, dzy, dxz);
    return;
  }
  if (!ddepth) throw std::invalid_argument("stage joints backward: depth maps without their gradient");
  std::vector<float> xy_only(dj, dj + std::size_t(xy.n) * xy.c * 3);
  for (std::size_t k = 2; k < xy_only.size(); k += 3) xy_only[k] = 0.f;
  dsnt_joints_backward(xy_only.data(), dxy, dzy, dxz);
  expected_depth_backward(dj, xy, *depth, dxy, *ddepth);
}

}  // namespace yelan::layers
