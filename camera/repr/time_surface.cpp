#include "camera/repr/time_surface.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace yelan::camera {
namespace {
constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
}

TimeSurface::TimeSurface(int width, int height, std::int64_t tau_us)
    : width_(width), height_(height), plane_(std::size_t(width) * height), tau_(tau_us) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw std::invalid_argument("time surface: sensor size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is outside 1..65536");
  if (tau_us <= 0) throw std::invalid_argument("time surface: tau must be positive");
  last_.assign(2 * plane_, kNever);
}

void TimeSurface::reset() {
  std::fill(last_.begin(), last_.end(), kNever);
  out_of_range_ = 0;
}

void TimeSurface::readout(std::int64_t t_us, float* out) const {
  const double inv_tau = 1.0 / double(tau_);
  for (std::size_t i = 0; i < last_.size(); ++i) {
    const std::int64_t t = last_[i];
    // Compare before subtracting: T - kNever would overflow.
    out[i] = (t == kNever || t > t_us) ? 0.f : static_cast<float>(std::exp(-(double(t_us) - double(t)) * inv_tau));
  }
}

}  // namespace yelan::camera
