// A picture of stage 1 against the truth (`yelan eval --mask-pictures DIR`): where the mask
// net is wrong, seen at a glance, which the IoU alone does not say (a missed arm, a moving
// curtain taken for a dancer, a dancer lost in low light).
#pragma once
#include <cstdint>
#include <vector>

namespace yelan::train {

struct MaskPictureColours {
  static constexpr std::uint8_t both[3] = {40, 200, 60};     // stage 1 and the truth
  static constexpr std::uint8_t net_only[3] = {230, 40, 40};  // stage 1 alone (false alarm)
  static constexpr std::uint8_t truth_only[3] = {50, 110, 255};  // the truth alone (missed)
};

// RGB bytes, sensor_h x sensor_w x 3. Under the colours above the TORE's newest planes in
// grey (the brighter of the two polarities, at 60%), so the events show through:
// a coloured pixel is the colour blended half and half with that grey.
// tore: 2K x sensor_h x sensor_w, channel-major (planes 0 and K are the newest);
// truth: sensor_h x sensor_w, nonzero = dancer; keep: the net's mask at mask_h x mask_w
// (the sensor downscaled by `down`), > 0 = dancer.
std::vector<std::uint8_t> mask_picture_rgb(const float* tore, int k, int sensor_h, int sensor_w,
                                           const std::uint8_t* truth, const float* keep, int mask_h, int mask_w,
                                           int down);

}  // namespace yelan::train
