#include "camera/sim/render.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

double Lighting::flicker(double t_s) const {
  return 1.0 + flicker_depth * std::cos(6.283185307179586 * flicker_hz * t_s);
}

namespace {

constexpr int kTile = 8;
constexpr double kNear = 10.0;  // mm: hits closer than this to the camera are ignored
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint64_t kPrintStream = 0x7072696e74ull;  // "print"

// Sub-pixel offsets for boundary pixels: n-rooks patterns (every sample has its own column
// and its own row), so an axis-aligned edge crossing the pixel flips one sample at a time.
constexpr double kRooks4[4][2] = {{-0.375, -0.125}, {-0.125, 0.375}, {0.125, -0.375},
                                  {0.375, 0.125}};
constexpr double kRooks8[8][2] = {{-0.4375, -0.0625}, {-0.3125, 0.3125}, {-0.1875, -0.3125},
                                  {-0.0625, 0.0625},  {0.0625, 0.4375},  {0.1875, -0.4375},
                                  {0.3125, -0.1875},  {0.4375, 0.1875}};
// 16 rooks: row index = 5 * column (mod 16), a well spread permutation.
struct Rooks16 {
  double o[16][2];
  constexpr Rooks16() : o{} {
    for (int i = 0; i < 16; ++i) {
      o[i][0] = (i + 0.5) / 16 - 0.5;
      o[i][1] = ((5 * i + 3) % 16 + 0.5) / 16 - 0.5;
    }
  }
};
constexpr Rooks16 kRooks16{};

// A primitive moved into the camera frame with everything a ray test needs precomputed.
struct Prepared {
  Shape shape = Shape::round_cone;
  bool human = false;
  bool one_sphere = false;  // round cone whose larger sphere swallows the other
  // round cone / cone shell: spheres (a, ra), (b, rb), unit axis w, length L
  Vec3 a, b, w;
  double L = 0, ra = 0, rb = 0, aa = 0, bb = 0, hw0 = 0;
  double s1 = 0, c1 = 0, c2 = 0, k = 0;  // cone: sin, cos, cos^2 of the side; shell slope
  double hlo = 0, hhi = 0;               // axial range of the lateral surface
  Vec3 bc;                               // bounding sphere (centre, |centre|^2 - r^2): a
  double bq = 0;                         //   cheap test that rejects most missing rays
  // ellipsoid: unit-sphere space is Ainv * (X - c)
  Eigen::Matrix3d Ainv, N;
  Vec3 o_unit;
  double oo = 0;
  // quad: corner a, edges e0, e1, normal n = e0 x e1, duals g0, g1
  Vec3 e0, e1, n, g0, g1;
  double na = 0;
  // material, frame in camera coordinates
  Vec3 morigin, mu, mv;
  double albedo = 0.5, albedo2 = 0.5, period = 60;
  Pattern pattern = Pattern::plain;
  std::uint64_t print_key = 0;  // per-cell hashes are mix64(print_key ^ cell)
  // screen pixel range (inclusive) and the nearest camera z any hit can have
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  double zmin = 0;
};

// Smallest root > kNear of DD t^2 - 2 (c.D) t + (cc - r^2) = 0, or kInf.
inline double hit_sphere(double cD, double cc, double r, double DD) {
  const double disc = cD * cD - DD * (cc - r * r);
  if (disc < 0) return kInf;
  const double s = std::sqrt(disc);
  double t = (cD - s) / DD;
  if (t > kNear) return t;
  t = (cD + s) / DD;
  return t > kNear ? t : kInf;
}

// Ray from the camera centre along D (D.z = 1). Returns the nearest hit in (kNear, tmax)
// in t and which surface it was on in part (0: sphere a, 1: sphere b, 2: the rest).
inline bool intersect(const Prepared& p, const Vec3& D, double DD, double tmax, double& t,
                      int& part) {
  double best = tmax;
  int bpart = -1;
  switch (p.shape) {
    case Shape::round_cone: {
      const double cD = p.bc.dot(D);
      if (cD * cD < DD * p.bq) return false;
      const double aD = p.a.dot(D);
      double ta = hit_sphere(aD, p.aa, p.ra, DD);
      if (ta < best) best = ta, bpart = 0;
      if (p.one_sphere) break;
      const double bD = p.b.dot(D);
      double tb = hit_sphere(bD, p.bb, p.rb, DD);
      if (tb < best) best = tb, bpart = 1;
      // Lateral cone: c2 (|X-a|^2 - h^2) = (ra - s1 h)^2 with h in [hlo, hhi].
      const double mD = -aD, dw = p.w.dot(D);
      const double q = p.ra - p.s1 * p.hw0;
      const double A = p.c2 * DD - dw * dw;
      const double hB = p.c2 * (mD - p.hw0 * dw) + q * p.s1 * dw;
      const double C = p.c2 * (p.aa - p.hw0 * p.hw0) - q * q;
      if (std::fabs(A) > 1e-12) {
        const double disc = hB * hB - A * C;
        if (disc >= 0) {
          const double s = std::sqrt(disc);
          const double r0 = (-hB - s) / A, r1 = (-hB + s) / A;
          for (double r : {std::min(r0, r1), std::max(r0, r1)}) {
            if (r <= kNear || r >= best) continue;
            const double h = p.hw0 + r * dw;
            if (h >= p.hlo && h <= p.hhi) {
              best = r, bpart = 2;
              break;
            }
          }
        }
      }
      break;
    }
    case Shape::cone_shell: {
      // |X-a|^2 - h^2 = (ra + k h)^2 with h in [0, L], both sheets of the open frustum.
      const double cD = p.bc.dot(D);
      if (cD * cD < DD * p.bq) return false;
      const double mD = -p.a.dot(D), dw = p.w.dot(D);
      const double q = p.ra + p.k * p.hw0;
      const double A = DD - dw * dw * (1 + p.k * p.k);
      const double hB = mD - p.hw0 * dw - p.k * dw * q;
      const double C = p.aa - p.hw0 * p.hw0 - q * q;
      double r0, r1;
      if (std::fabs(A) > 1e-12) {
        const double disc = hB * hB - A * C;
        if (disc < 0) break;
        const double s = std::sqrt(disc);
        r0 = (-hB - s) / A, r1 = (-hB + s) / A;
        if (r0 > r1) std::swap(r0, r1);
      } else {
        if (std::fabs(hB) < 1e-300) break;
        r0 = r1 = -C / (2 * hB);
      }
      for (double r : {r0, r1}) {
        if (r <= kNear || r >= best) continue;
        const double h = p.hw0 + r * dw;
        if (h >= 0 && h <= p.L) {
          best = r, bpart = 2;
          break;
        }
      }
      break;
    }
    case Shape::ellipsoid: {
      const Vec3 d = p.Ainv * D;
      const double dd = d.squaredNorm(), od = p.o_unit.dot(d);
      const double disc = od * od - dd * (p.oo - 1);
      if (disc < 0 || dd <= 0) break;
      const double s = std::sqrt(disc);
      double r = (-od - s) / dd;
      if (r <= kNear) r = (-od + s) / dd;
      if (r > kNear && r < best) best = r, bpart = 2;
      break;
    }
    case Shape::quad: {
      const double nD = p.n.dot(D);
      if (std::fabs(nD) < 1e-12) break;
      const double r = p.na / nD;
      if (r <= kNear || r >= best) break;
      const Vec3 rel = r * D - p.a;
      const double al = rel.dot(p.g0), be = rel.dot(p.g1);
      if (al >= 0 && al <= 1 && be >= 0 && be <= 1) best = r, bpart = 2;
      break;
    }
  }
  if (bpart < 0) return false;
  t = best;
  part = bpart;
  return true;
}

// Outward (for solids) unit normal at camera-frame point X on `part` of p.
inline Vec3 normal_at(const Prepared& p, int part, const Vec3& X) {
  switch (p.shape) {
    case Shape::round_cone: {
      if (part == 0) return (X - p.a).normalized();  // exact hits lie at ra; means inside
      if (part == 1) return (X - p.b).normalized();
      const Vec3 q = X - p.a;
      Vec3 radial = q - q.dot(p.w) * p.w;
      const double rn = radial.norm();
      radial = rn > 0 ? Vec3(radial / rn) : Vec3(p.w.unitOrthogonal());
      return p.c1 * radial + p.s1 * p.w;
    }
    case Shape::cone_shell: {
      const Vec3 q = X - p.a;
      Vec3 radial = q - q.dot(p.w) * p.w;
      const double rn = radial.norm();
      radial = rn > 0 ? Vec3(radial / rn) : Vec3(p.w.unitOrthogonal());
      return (radial - p.k * p.w).normalized();
    }
    case Shape::ellipsoid: return (p.N * (X - p.a)).normalized();
    case Shape::quad: return p.n.normalized();
  }
  return Vec3::UnitZ();
}

// Integral over [0, s] of the indicator of the second half of each unit period.
inline double square_integral(double s) {
  const double f = std::floor(s);
  return 0.5 * f + std::max(0.0, s - f - 0.5);
}

// Share of a box of width w (in periods) centred on s that falls on the second colour.
inline double stripe_share(double s, double w) {
  if (w < 1e-4) return (s - std::floor(s)) >= 0.5 ? 1.0 : 0.0;
  return (square_integral(s + 0.5 * w) - square_integral(s - 0.5 * w)) / w;
}

// Printed fabric: about 80% of the cells of a period-sized grid hold one disc of the second
// colour (centre and radius from the print seed). Edges are ramped over the footprint w (in
// cells) and the pattern fades to its mean once the footprint spans several blobs.
inline double print_share(double u, double v, double w, std::uint64_t key) {
  const double iu = std::floor(u), iv = std::floor(v);
  const double fu = u - iu, fv = v - iv;
  const int nu = fu < 0.5 ? -1 : 1, nv = fv < 0.5 ? -1 : 1;
  double cov = 0;
  for (int di : {0, nu})
    for (int dj : {0, nv}) {
      const auto ci = static_cast<std::uint32_t>(static_cast<std::int64_t>(iu) + di);
      const auto cj = static_cast<std::uint32_t>(static_cast<std::int64_t>(iv) + dj);
      const std::uint64_t h = mix64(key ^ ((std::uint64_t(ci) << 32) | cj));
      if ((h >> 56) >= 205) continue;
      const double bx = 0.2 + 0.6 * double(h & 0xffff) / 65536.0;
      const double by = 0.2 + 0.6 * double((h >> 16) & 0xffff) / 65536.0;
      const double r = 0.18 + 0.14 * double((h >> 32) & 0xffff) / 65536.0;
      const double dx = fu - di - bx, dy = fv - dj - by;
      const double d = std::sqrt(dx * dx + dy * dy);
      const double c = w > 1e-4 ? std::clamp(0.5 - (d - r) / w, 0.0, 1.0) : (d < r ? 1.0 : 0.0);
      cov = std::max(cov, c);
    }
  constexpr double kMean = 0.8 * 3.141592653589793 * 0.064133;  // 0.8 * pi * E[r^2]
  const double blend = std::clamp(w - 0.5, 0.0, 1.0);
  return cov + (kMean - cov) * blend;
}

struct ShadeContext {
  double fx, fy, level, ambient;
  Vec3 light;  // camera frame, towards the light
};

// Unflickered intensity of p's surface `part` at camera-frame point X (on the surface, or
// the mean of several hits on it), seen along the ray through X.
inline double shade(const Prepared& p, int part, const Vec3& X, const ShadeContext& ctx) {
  const double t = X.z();
  const Vec3 D = X * (1 / t);
  Vec3 n = normal_at(p, part, X);
  double nD = n.dot(D);
  if (nD > 0) n = -n, nD = -nD;  // two-sided surfaces and the inside of shells face the ray
  const double cosl = std::max(0.0, n.dot(ctx.light));
  double alb = p.albedo;
  if (p.pattern != Pattern::plain && p.period > 0) {
    // Ray differentials: the pixel's footprint on the tangent plane, in pattern units.
    const double inv_nD = 1 / std::min(nD, -0.02 * D.norm());
    const Vec3 dPdx = (t / ctx.fx) * (Vec3::UnitX() - D * (n.x() * inv_nD));
    const Vec3 dPdy = (t / ctx.fy) * (Vec3::UnitY() - D * (n.y() * inv_nD));
    const Vec3 rel = X - p.morigin;
    const double u = rel.dot(p.mu) / p.period, v = rel.dot(p.mv) / p.period;
    const double du = (std::fabs(p.mu.dot(dPdx)) + std::fabs(p.mu.dot(dPdy))) / p.period;
    const double dv = (std::fabs(p.mv.dot(dPdx)) + std::fabs(p.mv.dot(dPdy))) / p.period;
    double share = 0;
    switch (p.pattern) {
      case Pattern::stripes: share = stripe_share(u, du); break;
      case Pattern::checks: {
        const double a = stripe_share(u, du), b = stripe_share(v, dv);
        share = a * (1 - b) + b * (1 - a);
        break;
      }
      case Pattern::print: share = print_share(u, v, std::max(du, dv), p.print_key); break;
      case Pattern::plain: break;
    }
    alb = p.albedo + (p.albedo2 - p.albedo) * share;
  }
  return alb * ctx.level * (ctx.ambient + (1 - ctx.ambient) * cosl);
}

bool finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

struct Rect {
  double u0 = kInf, u1 = -kInf, v0 = kInf, v1 = -kInf;
  bool full = false;
  void add(double u, double v) {
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
};

// Adds the exact image bounds of a camera-frame sphere; false when it is wholly behind.
bool add_sphere(Rect& r, const Vec3& c, double rad, const CameraModel& cam) {
  if (c.z() + rad < kNear) return false;
  if (c.z() - rad <= kNear) {
    r.full = true;
    return true;
  }
  const double Z = c.z(), den = Z * Z - rad * rad;
  auto span = [&](double X, double& lo, double& hi) {
    const double root = std::sqrt(std::max(0.0, X * X + Z * Z - rad * rad));
    lo = (X * Z - rad * root) / den, hi = (X * Z + rad * root) / den;
  };
  double xl, xh, yl, yh;
  span(c.x(), xl, xh);
  span(c.y(), yl, yh);
  r.add(cam.fx * xl + cam.cx, cam.fy * yl + cam.cy);
  r.add(cam.fx * xh + cam.cx, cam.fy * yh + cam.cy);
  return true;
}

// Moves p into the camera frame and works out its screen range; false when it cannot be
// seen (behind the camera, off screen, degenerate or not finite).
bool prepare(const Primitive& prim, const CameraModel& cam, const Eigen::Matrix3d& R,
             const Vec3& tr, Prepared& p) {
  p = Prepared{};
  p.shape = prim.shape;
  p.human = prim.human;
  const Material& m = prim.material;
  p.albedo = m.albedo, p.albedo2 = m.albedo2, p.period = m.period_mm;
  p.pattern = m.pattern;
  p.print_key = mix64(mix64(m.print_seed) ^ kPrintStream);
  p.morigin = R * m.origin + tr, p.mu = R * m.u_axis, p.mv = R * m.v_axis;
  if (!finite(p.morigin) || !finite(p.mu) || !finite(p.mv) || !std::isfinite(p.period))
    p.pattern = Pattern::plain;
  Rect rect;
  bool visible = false;
  switch (prim.shape) {
    case Shape::round_cone:
    case Shape::cone_shell: {
      p.a = R * prim.a + tr, p.b = R * prim.b + tr;
      p.ra = std::max(0.0, prim.ra), p.rb = std::max(0.0, prim.rb);
      if (!finite(p.a) || !finite(p.b) || !std::isfinite(p.ra) || !std::isfinite(p.rb))
        return false;
      const Vec3 ab = p.b - p.a;
      p.L = ab.norm();
      if (prim.shape == Shape::round_cone) {
        if (p.L <= std::fabs(p.ra - p.rb) + 1e-9) {
          p.one_sphere = true;
          if (p.rb > p.ra) p.a = p.b, p.ra = p.rb;
          p.aa = p.a.squaredNorm();
          visible = add_sphere(rect, p.a, p.ra, cam);
          p.zmin = p.a.z() - p.ra;
          break;
        }
        p.w = ab / p.L;
        p.s1 = (p.ra - p.rb) / p.L;
        p.c2 = 1 - p.s1 * p.s1;
        p.c1 = std::sqrt(p.c2);
        p.hlo = p.ra * p.s1, p.hhi = p.L + p.rb * p.s1;
      } else {
        if (p.L < 1e-9) return false;
        p.w = ab / p.L;
        p.k = (p.rb - p.ra) / p.L;
      }
      p.aa = p.a.squaredNorm(), p.bb = p.b.squaredNorm(), p.hw0 = -p.a.dot(p.w);
      p.bc = 0.5 * (p.a + p.b);
      const double br = 0.5 * p.L + std::max(p.ra, p.rb) + 1.0;
      p.bq = p.bc.squaredNorm() - br * br;
      const bool va = add_sphere(rect, p.a, p.ra, cam), vb = add_sphere(rect, p.b, p.rb, cam);
      visible = va || vb;
      if (va != vb) rect.full = true;  // one end behind the camera: no tight bound
      p.zmin = std::min(p.a.z() - p.ra, p.b.z() - p.rb);
      break;
    }
    case Shape::ellipsoid: {
      p.a = R * prim.a + tr;
      const Eigen::Matrix3d A = R * prim.axes;
      if (!finite(p.a) || !A.allFinite() || std::fabs(A.determinant()) < 1e-9) return false;
      p.Ainv = A.inverse();
      p.N = p.Ainv.transpose() * p.Ainv;
      p.o_unit = -(p.Ainv * p.a);
      p.oo = p.o_unit.squaredNorm();
      const double rmax =
          std::max({A.col(0).norm(), A.col(1).norm(), A.col(2).norm()});
      visible = add_sphere(rect, p.a, rmax, cam);
      p.zmin = p.a.z() - rmax;
      break;
    }
    case Shape::quad: {
      p.a = R * prim.a + tr;
      p.e0 = R * prim.axes.col(0), p.e1 = R * prim.axes.col(1);
      p.n = p.e0.cross(p.e1);
      const double nn = p.n.squaredNorm();
      if (!finite(p.a) || !finite(p.e0) || !finite(p.e1) || !(nn > 1e-12)) return false;
      p.g0 = p.e1.cross(p.n) / nn, p.g1 = p.n.cross(p.e0) / nn;
      p.na = p.n.dot(p.a);
      const Vec3 corners[4] = {p.a, p.a + p.e0, p.a + p.e1, p.a + p.e0 + p.e1};
      int behind = 0;
      p.zmin = kInf;
      for (const Vec3& c : corners) {
        p.zmin = std::min(p.zmin, c.z());
        if (c.z() <= kNear) {
          ++behind;
          continue;
        }
        rect.add(cam.fx * c.x() / c.z() + cam.cx, cam.fy * c.y() / c.z() + cam.cy);
      }
      visible = behind < 4;
      if (behind > 0) rect.full = true;
      break;
    }
  }
  if (!visible) return false;
  if (rect.full) {
    p.x0 = 0, p.x1 = cam.width - 1, p.y0 = 0, p.y1 = cam.height - 1;
  } else {
    // Every pixel whose footprint [x-0.5, x+0.5] meets the bounds.
    if (!(rect.u0 <= rect.u1) || !(rect.v0 <= rect.v1)) return false;
    auto lo = [](double v, int n) {
      return int(std::clamp(std::ceil(v - 0.5 - 1e-6), -1.0, double(n)));
    };
    auto hi = [](double v, int n) {
      return int(std::clamp(std::floor(v + 0.5 + 1e-6), -1.0, double(n)));
    };
    p.x0 = std::max(0, lo(rect.u0, cam.width)), p.x1 = std::min(cam.width - 1, hi(rect.u1, cam.width));
    p.y0 = std::max(0, lo(rect.v0, cam.height)), p.y1 = std::min(cam.height - 1, hi(rect.v1, cam.height));
  }
  return p.x0 <= p.x1 && p.y0 <= p.y1;
}

// Two touching primitives of one material at about the same depth (an elbow, a shoulder)
// meet without a visible edge, so their seam is not supersampled.
inline bool seamless(const Prepared& a, const Prepared& b, double ta, double tb) {
  return a.albedo == b.albedo && a.albedo2 == b.albedo2 && a.pattern == b.pattern &&
         a.human == b.human && std::fabs(ta - tb) < 25.0;
}

// Primitives binned into screen tiles; each tile's list sorted by nearest possible depth.
struct Layer {
  std::vector<Prepared> prims;
  std::vector<int> begin;  // ntiles + 1 offsets into items
  std::vector<int> items;
  std::vector<int> count;

  void build(const std::vector<Primitive>& src, const CameraModel& cam, int ntx, int nty) {
    const Eigen::Matrix3d R = cam.M.leftCols<3>();
    const Vec3 tr = cam.M.col(3);
    prims.resize(src.size());
    std::size_t n = 0;
    for (const Primitive& s : src)
      if (prepare(s, cam, R, tr, prims[n])) ++n;
    prims.resize(n);
    const int ntiles = ntx * nty;
    count.assign(ntiles, 0);
    for (const Prepared& p : prims)
      for (int ty = p.y0 / kTile; ty <= p.y1 / kTile; ++ty)
        for (int tx = p.x0 / kTile; tx <= p.x1 / kTile; ++tx) ++count[ty * ntx + tx];
    begin.assign(ntiles + 1, 0);
    for (int i = 0; i < ntiles; ++i) begin[i + 1] = begin[i] + count[i];
    items.resize(begin[ntiles]);
    std::fill(count.begin(), count.end(), 0);
    for (int i = 0; i < int(prims.size()); ++i) {
      const Prepared& p = prims[i];
      for (int ty = p.y0 / kTile; ty <= p.y1 / kTile; ++ty)
        for (int tx = p.x0 / kTile; tx <= p.x1 / kTile; ++tx) {
          const int tile = ty * ntx + tx;
          items[begin[tile] + count[tile]++] = i;
        }
    }
    for (int tile = 0; tile < ntiles; ++tile)
      std::sort(items.begin() + begin[tile], items.begin() + begin[tile + 1], [&](int x, int y) {
        return prims[x].zmin < prims[y].zmin || (prims[x].zmin == prims[y].zmin && x < y);
      });
  }
  bool empty_tile(int tile) const { return begin[tile] == begin[tile + 1]; }
};

// Nearest hit among one tile's list for the ray through image point (x + ox, y + oy).
inline void cast(const Layer& layer, int tile, int x, int y, const Vec3& D, double DD,
                 int id_offset, double& best_t, int& best_id, int& best_part) {
  const int* it = layer.items.data() + layer.begin[tile];
  const int* end = layer.items.data() + layer.begin[tile + 1];
  for (; it != end; ++it) {
    const Prepared& p = layer.prims[*it];
    if (p.zmin >= best_t) break;
    if (x < p.x0 || x > p.x1 || y < p.y0 || y > p.y1) continue;
    double t;
    int part;
    if (intersect(p, D, DD, best_t, t, part)) best_t = t, best_id = id_offset + *it, best_part = part;
  }
}

}  // namespace

struct Renderer::Impl {
  RenderOptions opt;
  CameraModel cam;
  Lighting light;
  ShadeContext ctx{};
  int W = 0, H = 0, ntx = 0, nty = 0;
  Layer stat, dyn;
  // The static layer: anti-aliased unflickered intensity, centre depth, id and mask.
  std::vector<float> s_int, s_depth;
  std::vector<std::int32_t> s_id;
  std::vector<std::uint8_t> s_mask;
  // 1 where the static layer shows one surface over the pixel's whole 3x3 neighbourhood:
  // there a sub-pixel ray that misses every moving primitive sees the cached value.
  std::vector<std::uint8_t> s_flat;
  double inv_fx = 1, inv_fy = 1;
  // Per-frame centre hits inside tiles the dynamic layer touches.
  // Centre hits of the static layer and the current frame combined: tiles the dynamic layer
  // touched last frame are reset from the static layer before the next frame.
  std::vector<std::int32_t> c_id;
  std::vector<double> c_t;
  std::vector<int> touched;
  std::vector<std::uint8_t> c_part;
  bool ready = false;

  int threads() const { return opt.threads > 0 ? opt.threads : omp_get_max_threads(); }

  void setup(const CameraModel& c, const Lighting& l) {
    if (c.width < 1 || c.height < 1 || c.width > 65536 || c.height > 65536)
      throw std::invalid_argument("render: image size " + std::to_string(c.width) + "x" +
                                  std::to_string(c.height) + " is outside 1..65536");
    if (!(c.fx > 0) || !(c.fy > 0) || !std::isfinite(c.fx) || !std::isfinite(c.fy) ||
        !std::isfinite(c.cx) || !std::isfinite(c.cy) || !c.M.allFinite())
      throw std::invalid_argument("render: camera intrinsics/extrinsics are not finite and positive");
    if (opt.edge_samples != 1 && opt.edge_samples != 4 && opt.edge_samples != 8 &&
        opt.edge_samples != 16)
      throw std::invalid_argument("render: edge_samples must be 1, 4, 8 or 16, not " +
                                  std::to_string(opt.edge_samples));
    cam = c, light = l;
    W = c.width, H = c.height;
    ntx = (W + kTile - 1) / kTile, nty = (H + kTile - 1) / kTile;
    ctx.fx = c.fx, ctx.fy = c.fy;
    inv_fx = 1 / c.fx, inv_fy = 1 / c.fy;
    ctx.level = l.level, ctx.ambient = std::clamp(l.ambient, 0.0, 1.0);
    const Vec3 kd = c.M.leftCols<3>() * l.key_dir;
    ctx.light = kd.norm() > 0 ? Vec3(kd.normalized()) : Vec3::Zero();
    const std::size_t n = std::size_t(W) * H;
    s_int.assign(n, 0.f);
    s_depth.assign(n, std::numeric_limits<float>::infinity());
    s_id.assign(n, -1);
    s_mask.assign(n, 0);
    s_flat.assign(n, 0);
    c_id.assign(n, -1);
    c_t.assign(n, kInf);
    touched.clear();
    c_part.assign(n, 0);
    stat.build({}, cam, ntx, nty);
    ready = true;
  }

  Vec3 ray(double x, double y) const {
    return Vec3((x - cam.cx) * inv_fx, (y - cam.cy) * inv_fy, 1.0);
  }

  // Composites `dyn` onto the static layer into out, intensities times `gain`.
  void frame(double gain, RenderedFrame& out) {
    const std::size_t n = std::size_t(W) * H;
    out.width = W, out.height = H;
    out.intensity.resize(n);
    out.mask.resize(n);
    out.depth_mm.resize(n);
    const int S = int(stat.prims.size());
    const int nt = threads();
    const float fgain = float(gain);

    for (int tile : touched) {
      const int tx = tile % ntx, ty = tile / ntx;
      for (int y = ty * kTile; y < std::min(H, (ty + 1) * kTile); ++y)
        for (int x = tx * kTile; x < std::min(W, (tx + 1) * kTile); ++x) {
          const std::size_t i = std::size_t(y) * W + x;
          c_id[i] = s_id[i], c_t[i] = s_depth[i];
        }
    }
    touched.clear();
    for (int tile = 0; tile < ntx * nty; ++tile)
      if (!dyn.empty_tile(tile)) touched.push_back(tile);

    // Row y's columns in tile tx: none where the dynamic layer does not touch the tile.
    auto touched_columns = [&](int y, int tx) {
      const int x0 = tx * kTile;
      return std::pair{x0, dyn.empty_tile((y / kTile) * ntx + tx) ? x0 : std::min(W, x0 + kTile)};
    };

    // Pass 1: centre rays of every pixel in a tile the dynamic layer touches.
#pragma omp parallel for schedule(dynamic, 4) num_threads(nt) if (nt > 1)
    for (int y = 0; y < H; ++y) {
      for (int tx = 0; tx < ntx; ++tx) {
        const auto [x0, xe] = touched_columns(y, tx);
        for (int x = x0; x < xe; ++x) {
          const std::size_t i = std::size_t(y) * W + x;
          const Vec3 D = ray(x, y);
          const double DD = D.squaredNorm();
          double bt = s_depth[i];
          int bid = s_id[i], bpart = 0;
          cast(dyn, (y / kTile) * ntx + tx, x, y, D, DD, S, bt, bid, bpart);
          c_id[i] = bid, c_t[i] = bt, c_part[i] = std::uint8_t(bpart);
        }
      }
    }

    // Pass 2: shade; supersample pixels whose neighbourhood holds another primitive.
    const int ns = opt.edge_samples;
    const double(*offs)[2] = ns == 4 ? kRooks4 : ns == 8 ? kRooks8 : kRooks16.o;
#pragma omp parallel for schedule(dynamic, 4) num_threads(nt) if (nt > 1)
    for (int y = 0; y < H; ++y) {
      const std::size_t row = std::size_t(y) * W;
      for (int x = 0; x < W; ++x) {
        out.intensity[row + x] = s_int[row + x] * fgain;
        out.depth_mm[row + x] = s_depth[row + x];
        out.mask[row + x] = s_mask[row + x];
      }
      for (int tx = 0; tx < ntx; ++tx) {
        const auto [x0, xe] = touched_columns(y, tx);
        for (int x = x0; x < xe; ++x) {
          const std::size_t i = row + x;
          const int id = c_id[i];
          bool edge = false, dynamic_near = id >= S;
          int near_ids[9], n_near = 0;  // distinct surfaces seen by the 3x3 centre rays
          for (int dy = -1; dy <= 1; ++dy) {
            const int yy = y + dy;
            if (yy < 0 || yy >= H) continue;
            for (int dx = -1; dx <= 1; ++dx) {
              const int xx = x + dx;
              if (xx < 0 || xx >= W) continue;
              const std::size_t j = std::size_t(yy) * W + xx;
              const int nid = c_id[j];
              if (nid >= S) dynamic_near = true;
              int k = 0;
              while (k < n_near && near_ids[k] != nid) ++k;
              if (k == n_near) near_ids[n_near++] = nid;
              if (nid != id && !(id >= S && nid >= S && seamless(dyn.prims[id - S],
                                                                 dyn.prims[nid - S], c_t[i], c_t[j])))
                edge = true;
            }
          }
          if (!dynamic_near) continue;  // only static surfaces here: the cached value stands
          const Prepared* hp = id >= S ? &dyn.prims[id - S] : nullptr;
          if (id >= S) {
            out.depth_mm[i] = float(c_t[i]);
            out.mask[i] = hp->human ? 1 : 0;
          }
          if (!edge || ns == 1) {
            if (hp) out.intensity[i] = float(shade(*hp, c_part[i], c_t[i] * ray(x, y), ctx)) * fgain;
            continue;
          }
          // Cast every sub-pixel ray against the surfaces the neighbouring centre rays saw
          // (a feature thinner than a pixel between them is missed, as by the centre rays),
          // then shade each surface once at the mean of its hits, weighted by its share of
          // the rays: smooth in the edge position, few shadings.
          std::sort(near_ids, near_ids + n_near);
          struct Group {
            int id, part, n;
            Vec3 sum;
          } groups[16];
          int ng = 0, nbg = 0;
          const int sid = s_id[i];
          const bool flat = s_flat[i];
          for (int s = 0; s < ns; ++s) {
            const Vec3 D = ray(x + offs[s][0], y + offs[s][1]);
            const double DD = D.squaredNorm();
            double bt = kInf;
            int bid = -1, bpart = 0;
            double ts;
            int pt;
            for (int k = 0; k < n_near; ++k) {
              const int c = near_ids[k];
              if (c < 0 || (flat && c < S)) continue;
              if (intersect(c >= S ? dyn.prims[c - S] : stat.prims[c], D, DD, bt, ts, pt))
                bt = ts, bid = c, bpart = pt;
            }
            if (flat) {
              if (bid < 0) {
                ++nbg;
                continue;
              }
              if (sid >= 0 && intersect(stat.prims[sid], D, DD, bt, ts, pt))
                bt = ts, bid = sid, bpart = pt;
            }
            if (bid < 0) continue;
            int g = 0;
            while (g < ng && (groups[g].id != bid || groups[g].part != bpart)) ++g;
            if (g == ng) groups[ng++] = Group{bid, bpart, 0, Vec3::Zero()};
            groups[g].n += 1;
            groups[g].sum += bt * D;
          }
          double sum = nbg * double(s_int[i]);
          for (int g = 0; g < ng; ++g) {
            const Prepared& p = groups[g].id >= S ? dyn.prims[groups[g].id - S] : stat.prims[groups[g].id];
            sum += groups[g].n * shade(p, groups[g].part, groups[g].sum / groups[g].n, ctx);
          }
          out.intensity[i] = float(sum / ns) * fgain;
        }
      }
    }
  }
};

Renderer::Renderer(RenderOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = options;
}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

const CameraModel& Renderer::camera() const { return impl_->cam; }

void Renderer::set_static(const CameraModel& cam, const std::vector<Primitive>& static_prims,
                          const Lighting& light) {
  Impl& m = *impl_;
  m.setup(cam, light);
  m.dyn.build(static_prims, m.cam, m.ntx, m.nty);
  RenderedFrame layer;
  m.frame(1.0, layer);
  m.s_int = std::move(layer.intensity);
  m.s_depth = std::move(layer.depth_mm);
  m.s_mask = std::move(layer.mask);
  m.s_id = m.c_id;
  for (int y = 0; y < m.H; ++y)
    for (int x = 0; x < m.W; ++x) {
      bool flat = true;
      const int id = m.s_id[std::size_t(y) * m.W + x];
      for (int yy = std::max(0, y - 1); yy <= std::min(m.H - 1, y + 1); ++yy)
        for (int xx = std::max(0, x - 1); xx <= std::min(m.W - 1, x + 1); ++xx)
          flat = flat && m.s_id[std::size_t(yy) * m.W + xx] == id;
      m.s_flat[std::size_t(y) * m.W + x] = flat;
    }
  for (std::size_t i = 0; i < m.c_t.size(); ++i) m.c_t[i] = m.s_depth[i];
  m.touched.clear();
  std::swap(m.stat, m.dyn);
  m.dyn.build({}, m.cam, m.ntx, m.nty);
}

void Renderer::render(double t_s, const std::vector<Primitive>& dynamic_prims,
                      RenderedFrame& out) {
  Impl& m = *impl_;
  if (!m.ready) throw std::logic_error("Renderer::render before set_static");
  m.dyn.build(dynamic_prims, m.cam, m.ntx, m.nty);
  m.frame(m.light.flicker(t_s), out);
}

void Renderer::render_unflickered(const std::vector<Primitive>& dynamic_prims, RenderedFrame& out) {
  Impl& m = *impl_;
  if (!m.ready) throw std::logic_error("Renderer::render_unflickered before set_static");
  m.dyn.build(dynamic_prims, m.cam, m.ntx, m.nty);
  m.frame(1.0, out);
}

void render(const CameraModel& cam, const std::vector<Primitive>& prims, const Lighting& light,
            double t_s, RenderedFrame& out, const RenderOptions& options) {
  Renderer r(options);
  r.set_static(cam, {}, light);
  r.render(t_s, prims, out);
}

}  // namespace yelan::camera::sim
