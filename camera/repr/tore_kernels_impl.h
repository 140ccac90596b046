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

// Ages are unsigned wrapped differences: a future event (t > T) or an empty slot
// (INT64_MIN) becomes a huge age and falls outside every horizon below 2^31.
void tore_yelan_impl(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p,
                     float* out) {
  const std::uint64_t t = static_cast<std::uint64_t>(p.t);
  const std::uint32_t horizon = static_cast<std::uint32_t>(p.horizon);
  for (std::size_t i = 0; i < n; ++i) {
    // The 64-bit age tested as two 32-bit halves: baseline x86-64 (SSE2) has no 64-bit
    // compare, and this form lets GCC vectorise there too.
    const std::uint64_t age = t - static_cast<std::uint64_t>(stamps[i]);
    const std::uint32_t lo = static_cast<std::uint32_t>(age), hi = static_cast<std::uint32_t>(age >> 32);
    const bool live = (hi == 0) & (lo < horizon);
    // Exact for live ages (< 2^31); dead ones are masked below.
    const float a = static_cast<float>(static_cast<std::int32_t>(lo & 0x7fffffffu));
    const float v = std::clamp(p.offset - p.scale * fast_ln(1.f + a), 0.f, 1.f);
    out[i] = live ? v : 0.f;
  }
}

void tore_baldwin_impl(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p,
                       float* out) {
  const std::uint64_t t = static_cast<std::uint64_t>(p.t);
  const std::uint32_t horizon = static_cast<std::uint32_t>(p.horizon);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t age = t - static_cast<std::uint64_t>(stamps[i]);
    const std::uint32_t lo = static_cast<std::uint32_t>(age), hi = static_cast<std::uint32_t>(age >> 32);
    const std::uint32_t clipped = (hi == 0) & (lo < horizon) ? lo : horizon;  // min(age, max_t)
    const float a = static_cast<float>(static_cast<std::int32_t>(clipped));
    out[i] = std::max(fast_ln(1.f + a) - p.offset, 0.f);
  }
}

}  // namespace
}  // namespace yelan::camera
