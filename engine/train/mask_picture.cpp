#include "engine/train/mask_picture.h"

#include <algorithm>
#include <cstddef>

namespace yelan::train {

std::vector<std::uint8_t> mask_picture_rgb(const float* tore, int k, int sensor_h, int sensor_w,
                                           const std::uint8_t* truth, const float* keep, int mask_h, int mask_w,
                                           int down) {
  const std::size_t plane = std::size_t(sensor_h) * std::size_t(sensor_w);
  std::vector<std::uint8_t> rgb(plane * 3);
  for (int y = 0; y < sensor_h; ++y)
    for (int x = 0; x < sensor_w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(sensor_w) + std::size_t(x);
      const float v = std::clamp(std::max(tore[i], tore[std::size_t(k) * plane + i]), 0.f, 1.f);
      const int g = int(0.6f * 255.f * v + 0.5f);
      // Pixels past the last whole cell of the downscale (sensor 346 at /4) have no mask cell.
      const int my = y / down, mx = x / down;
      const bool net = my < mask_h && mx < mask_w && keep[std::size_t(my) * std::size_t(mask_w) + std::size_t(mx)] > 0;
      const bool tr = truth[i] != 0;
      const std::uint8_t* c = net && tr ? MaskPictureColours::both
                              : net     ? MaskPictureColours::net_only
                              : tr      ? MaskPictureColours::truth_only
                                        : nullptr;
      for (int ch = 0; ch < 3; ++ch) rgb[3 * i + std::size_t(ch)] = std::uint8_t(c ? (c[ch] + g) / 2 : g);
    }
  return rgb;
}

}  // namespace yelan::train
