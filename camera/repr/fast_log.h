// A branch-free natural logarithm for float that the compiler can vectorise (std::log is a
// library call per element and blocks auto-vectorisation). Valid for positive, normal,
// finite x; the TORE read-out only calls it on 1 + age with age in [0, 2^31).
// Max error against std::log in double, measured over every float in [1/16, 2^31]:
// 1.03e-6 absolute (at x ~ 4.6e7, where that is half an ulp of the result), and at most
// 2.9 ulp of the result wherever |ln x| > 1e-3. tests/camera_repr checks both bounds.
//
// The definitions are in an unnamed namespace on purpose: the header is compiled into
// ISA-specific translation units (AVX2, AVX-512 flags), and an inline function with
// external linkage could be merged by the linker with an AVX copy and then run on a CPU
// without AVX.
#pragma once
#include <bit>
#include <cstdint>

namespace yelan::camera {
namespace {

inline float fast_ln(float x) {
  // x = m * 2^e with m in [sqrt(1/2), sqrt(2)): shift the bit pattern so that the exponent
  // field rounds at sqrt(2) instead of 2, keeping |s| below 0.172 in the series below.
  constexpr std::int32_t kSqrtHalfBits = 0x3f3504f3;
  const std::int32_t bits = std::bit_cast<std::int32_t>(x) - kSqrtHalfBits;
  const std::int32_t e = bits >> 23;  // arithmetic shift: floor of the exponent
  const float m = std::bit_cast<float>((bits & 0x007fffff) + kSqrtHalfBits);
  // ln(m) = 2 atanh(s), s = (m - 1) / (m + 1); the truncated series errs below 1e-9.
  const float s = (m - 1.f) / (m + 1.f);
  const float z = s * s;
  const float poly = 1.f + z * (1.f / 3 + z * (1.f / 5 + z * (1.f / 7 + z * (1.f / 9))));
  // ln 2 split in a part exact in float and a correction, so e * ln 2 keeps full precision.
  constexpr float kLn2Hi = 0.693145751953125f, kLn2Lo = 1.428606765330187e-06f;
  const float fe = static_cast<float>(e);
  return fe * kLn2Hi + (2.f * s * poly + fe * kLn2Lo);
}

}  // namespace
}  // namespace yelan::camera
