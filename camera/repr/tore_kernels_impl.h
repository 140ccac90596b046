// The body of every TORE read-out kernel variant: plain loops written so that GCC
// vectorises them at whatever ISA the including file is compiled for. Internal linkage
// only (see fast_log.h for why).
#pragma once
#include <algorithm>
#include <cstdint>

#include "camera/repr/fast_log.h"
#include "camera/repr/tore_kernels.h"

namespace yelan::camera {
namespace {

// An event's age at t, clipped to the horizon: ages are unsigned wrapped differences, so a
// future event (stamp > t) or an empty slot (INT64_MIN) becomes a huge age and clips like
// any age past a horizon below 2^31. The 64-bit age is tested as two 32-bit halves:
// baseline x86-64 (SSE2) has no 64-bit compare, and this form lets GCC vectorise there too.
inline std::uint32_t clipped_age(std::uint64_t t, std::int64_t stamp, std::uint32_t horizon) {
  const std::uint64_t age = t - static_cast<std::uint64_t>(stamp);
  const std::uint32_t lo = static_cast<std::uint32_t>(age), hi = static_cast<std::uint32_t>(age >> 32);
  return (hi == 0) & (lo < horizon) ? lo : horizon;
}

void tore_yelan_impl(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p,
                     float* out) {
  const std::uint64_t t = static_cast<std::uint64_t>(p.t);
  const std::uint32_t horizon = static_cast<std::uint32_t>(p.horizon);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t age = clipped_age(t, stamps[i], horizon);
    // Exact: a clipped age is below 2^31.
    const float a = static_cast<float>(static_cast<std::int32_t>(age));
    const float v = std::clamp(p.offset - p.scale * fast_ln(1.f + a), 0.f, 1.f);
    out[i] = age < horizon ? v : 0.f;
  }
}

void tore_baldwin_impl(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p,
                       float* out) {
  const std::uint64_t t = static_cast<std::uint64_t>(p.t);
  const std::uint32_t horizon = static_cast<std::uint32_t>(p.horizon);
  for (std::size_t i = 0; i < n; ++i) {
    const float a = static_cast<float>(static_cast<std::int32_t>(clipped_age(t, stamps[i], horizon)));
    out[i] = std::max(fast_ln(1.f + a) - p.offset, 0.f);
  }
}

}  // namespace
}  // namespace yelan::camera
