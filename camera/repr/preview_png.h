// Pictures of representation volumes for eyes (`yelan repr --png`): 8-bit RGB PNG via
// libpng, written atomically (temp file + rename).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace yelan::camera {

// How channels map to colour. Values are clamped to [0, 1] (signed: to [-1, 1]).
enum class PreviewStyle {
  polarity_pair,  // channel `a` -> red, channel `b` -> blue (TORE pos0/neg0, surface ON/OFF)
  grey,           // channel `a` as grey (count frames)
  signed_value,   // channel `a`: positive -> red, negative -> blue (a voxel bin)
};

// RGB bytes (height x width x 3) of one channel-major volume.
std::vector<std::uint8_t> preview_rgb(const float* volume, int width, int height,
                                      PreviewStyle style, int a, int b = 0, float gain = 1.f);

// Throws std::runtime_error naming the path on failure; `path` is untouched then.
void write_png_rgb(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb);

}  // namespace yelan::camera
