#include "camera/repr/preview_png.h"

#include "camera/io/temp_file.h"

#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

namespace yelan::camera {
namespace {

std::uint8_t to_byte(float v) { return static_cast<std::uint8_t>(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f); }

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// libpng reports errors by longjmp unless the error callback throws; C++ exceptions
// through libpng's C frames are fine with GCC on Linux (it is built with unwind tables).
[[noreturn]] void png_error_throw(png_structp, png_const_charp msg) { throw std::runtime_error(msg); }
void png_warning_ignore(png_structp, png_const_charp) {}

}  // namespace

std::vector<std::uint8_t> preview_rgb(const float* volume, int width, int height, PreviewStyle style,
                                      int a, int b, float gain) {
  const std::size_t plane = std::size_t(width) * height;
  std::vector<std::uint8_t> rgb(plane * 3, 0);
  const float* ca = volume + std::size_t(a) * plane;
  const float* cb = volume + std::size_t(b) * plane;
  for (std::size_t i = 0; i < plane; ++i) {
    std::uint8_t* px = &rgb[3 * i];
    switch (style) {
      case PreviewStyle::polarity_pair:
        px[0] = to_byte(gain * ca[i]);
        px[2] = to_byte(gain * cb[i]);
        break;
      case PreviewStyle::grey:
        px[0] = px[1] = px[2] = to_byte(gain * ca[i]);
        break;
      case PreviewStyle::signed_value:
        px[0] = to_byte(gain * ca[i]);
        px[2] = to_byte(-gain * ca[i]);
        break;
    }
  }
  return rgb;
}

void write_png_rgb(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != std::size_t(width) * height * 3)
    throw std::runtime_error(path + ": cannot write PNG: pixel buffer does not match " +
                             std::to_string(width) + "x" + std::to_string(height));
  TempFile tmp_file(path);
  const std::string& tmp = tmp_file.path();
  {
    std::unique_ptr<std::FILE, FileCloser> file(std::fopen(tmp.c_str(), "wb"));
    if (!file) throw std::runtime_error(path + ": cannot write PNG: cannot create " + tmp);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, png_error_throw,
                                              png_warning_ignore);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    try {
      if (!info) throw std::runtime_error("out of memory");
      png_init_io(png, file.get());
      png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB,
                   PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
      png_write_info(png, info);
      for (int y = 0; y < height; ++y) png_write_row(png, &rgb[std::size_t(y) * width * 3]);
      png_write_end(png, nullptr);
      png_destroy_write_struct(&png, &info);
      if (std::fflush(file.get()) != 0) throw std::runtime_error("write failed");
    } catch (const std::exception& e) {
      png_destroy_write_struct(&png, &info);
      file.reset();
      throw std::runtime_error(path + ": cannot write PNG: " + e.what());
    }
  }
  try {
    tmp_file.commit();
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": cannot write PNG: " + e.what());
  }
}

}  // namespace yelan::camera
