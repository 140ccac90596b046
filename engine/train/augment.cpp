#include "engine/train/augment.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace yelan::train {

Similarity draw_similarity(camera::sim::Rng& r, int sensor_w, int sensor_h) {
  Similarity s;
  s.scale = std::exp(r.uniform(std::log(0.8), std::log(1.25)));
  s.angle_rad = r.uniform(-15.0, 15.0) * 3.141592653589793 / 180;
  s.shift_x = r.uniform(-0.1, 0.1) * sensor_w;
  s.shift_y = r.uniform(-0.1, 0.1) * sensor_h;
  return s;
}

Similarity framing_similarity(const camera::sim::SimWindow& w, int first, int count, double grow, double most) {
  const auto& k = w.camera;
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  for (int t = first; t < first + count && t < int(w.frames.size()); ++t) {
    const auto& f = w.frames[std::size_t(t)];
    for (int j = 0; j < camera::sim::kJointCount; ++j) {
      const auto& p = f.joints_mm[std::size_t(j)];
      if (!f.valid[std::size_t(j)] || !(p.z() > 1)) continue;
      const double u = k.fx * p.x() / p.z() + k.cx, v = k.fy * p.y() / p.z() + k.cy;
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
  }
  Similarity s;
  if (u0 > u1) return s;
  const double bw = std::max(1.0, (u1 - u0) * (1 + 2 * grow)), bh = std::max(1.0, (v1 - v0) * (1 + 2 * grow));
  s.scale = std::clamp(std::min(k.width / bw, k.height / bh), 1.0, most);
  s.shift_x = -s.scale * ((u0 + u1) / 2 - 0.5 * k.width);
  s.shift_y = -s.scale * ((v0 + v1) / 2 - 0.5 * k.height);
  return s;
}

std::array<double, 2> warp_point(const Similarity& s, double u, double v, int sensor_w, int sensor_h) {
  const double cx = 0.5 * sensor_w, cy = 0.5 * sensor_h, c = std::cos(s.angle_rad), sn = std::sin(s.angle_rad);
  const double x = u - cx, y = v - cy;
  return {cx + s.scale * (c * x - sn * y) + s.shift_x, cy + s.scale * (sn * x + c * y) + s.shift_y};
}

void warp_frame(const layers::Act& a, int n, const Similarity& s, int d, int sensor_w, int sensor_h) {
  const int H = a.h, W = a.w;
  const double cx = 0.5 * sensor_w, cy = 0.5 * sensor_h, c = std::cos(s.angle_rad), sn = std::sin(s.angle_rad);
  std::vector<float> src;
  for (int cb = 0; cb < a.cb(); ++cb) {
    float* p = a.data + (std::size_t(n) * a.cb() + cb) * a.pixels() * 16;
    src.assign(p, p + a.pixels() * 16);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        // The output cell's centre in sensor pixels, back through the inverse warp, then
        // into source cells (whose centres sit at (i + 0.5) d).
        const double u = (x + 0.5) * d - cx - s.shift_x, v = (y + 0.5) * d - cy - s.shift_y;
        const double su = (c * u + sn * v) / s.scale + cx, sv = (-sn * u + c * v) / s.scale + cy;
        const double fx = su / d - 0.5, fy = sv / d - 0.5;
        const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
        const float ax = float(fx - x0), ay = float(fy - y0);
        float* o = p + (std::size_t(y) * W + x) * 16;
        for (int l = 0; l < 16; ++l) o[l] = 0;
        for (int k = 0; k < 4; ++k) {
          const int xx = x0 + (k & 1), yy = y0 + (k >> 1);
          if (xx < 0 || xx >= W || yy < 0 || yy >= H) continue;
          const float wgt = ((k & 1) ? ax : 1 - ax) * ((k >> 1) ? ay : 1 - ay);
          const float* q = src.data() + (std::size_t(yy) * W + xx) * 16;
          for (int l = 0; l < 16; ++l) o[l] += wgt * q[l];
        }
      }
  }
}

std::array<double, 3> warp_joint(const Similarity& s, const std::array<double, 3>& p, const Intrinsics& k, double z_ref) {
  const double u = k.fx * p[0] / p[2] + k.cx, v = k.fy * p[1] / p[2] + k.cy;
  const auto [u2, v2] = warp_point(s, u, v, k.width, k.height);
  const double z = p[2] - z_ref + z_ref / s.scale;
  return {(u2 - k.cx) * z / k.fx, (v2 - k.cy) * z / k.fy, z};
}

std::array<double, 3> flip_joint(const std::array<double, 3>& p, const Intrinsics& k, int cells_w, int d) {
  const double u = k.fx * p[0] / p[2] + k.cx, u2 = double(cells_w) * d - u;
  return {(u2 - k.cx) * p[2] / k.fx, p[1], p[2]};
}

}  // namespace yelan::train
