#include "engine/train/mask_overlap.h"

#include <cstddef>
#include <vector>

namespace yelan::train {

MaskOverlap& MaskOverlap::operator+=(const MaskOverlap& o) {
  inter += o.inter;
  uni += o.uni;
  inter_off_edge += o.inter_off_edge;
  uni_off_edge += o.uni_off_edge;
  inter_px += o.inter_px;
  uni_px += o.uni_px;
  return *this;
}

MaskOverlap MaskOverlap::operator-(const MaskOverlap& o) const {
  return {inter - o.inter, uni - o.uni, inter_off_edge - o.inter_off_edge, uni_off_edge - o.uni_off_edge,
          inter_px - o.inter_px, uni_px - o.uni_px};
}

void add_mask_overlap(MaskOverlap& m, const std::uint8_t* truth, int sensor_w, const float* keep, int mask_h,
                      int mask_w, int down) {
  std::vector<std::uint8_t> t(std::size_t(mask_h) * std::size_t(mask_w));
  for (int y = 0; y < mask_h; ++y)
    for (int x = 0; x < mask_w; ++x)
      t[std::size_t(y) * std::size_t(mask_w) + std::size_t(x)] =
          truth[std::size_t(y * down + down / 2) * std::size_t(sensor_w) + std::size_t(x * down + down / 2)] != 0;
  for (int y = 0; y < mask_h; ++y)
    for (int x = 0; x < mask_w; ++x) {
      const std::size_t i = std::size_t(y) * std::size_t(mask_w) + std::size_t(x);
      const bool pr = keep[i] > 0, tr = t[i] != 0;
      m.inter += pr && tr;
      m.uni += pr || tr;
      bool edge = false;  // a neighbour (inside the frame) of the other class
      for (int dy = -1; dy <= 1 && !edge; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int yy = y + dy, xx = x + dx;
          if (yy < 0 || xx < 0 || yy >= mask_h || xx >= mask_w) continue;
          if ((t[std::size_t(yy) * std::size_t(mask_w) + std::size_t(xx)] != 0) != tr) {
            edge = true;
            break;
          }
        }
      if (!edge) {
        m.inter_off_edge += pr && tr;
        m.uni_off_edge += pr || tr;
      }
    }
  for (int y = 0; y < mask_h * down; ++y) {
    const float* cells = keep + std::size_t(y / down) * std::size_t(mask_w);
    const std::uint8_t* row = truth + std::size_t(y) * std::size_t(sensor_w);
    for (int x = 0; x < mask_w * down; ++x) {
      const bool pr = cells[x / down] > 0, tr = row[x] != 0;
      m.inter_px += pr && tr;
      m.uni_px += pr || tr;
    }
  }
}

std::map<std::string, double> measured_iou(const std::map<std::string, MaskOverlap>& by_key, bool sensor_px) {
  std::map<std::string, double> out;
  for (const auto& [key, m] : by_key)
    if ((sensor_px ? m.uni_px : m.uni) > 0) out[key] = sensor_px ? m.iou_px() : m.iou();
  return out;
}

}  // namespace yelan::train
