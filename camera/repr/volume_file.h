// Writes representation volumes to HDF5 as they are produced (bounded memory): dataset
// `volumes` (N x C x H x W float32, chunked one volume per chunk, gzip level 1) and `t`
// (N int64, microseconds), root attributes `format = "yelan-repr"`, `type`, and whatever
// integer attributes the caller adds. The file appears atomically: everything goes to
// a TempFile beside `path`, renamed over it by finish(); a writer destroyed without finish()
// removes its temporary file and leaves `path` untouched.
#pragma once
#include <memory>

#include "camera/io/temp_file.h"
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace yelan::camera {

class VolumeFileWriter {
 public:
  // Throws std::runtime_error naming the path when the file cannot be created.
  VolumeFileWriter(std::string path, std::string type, int channels, int height, int width,
                   const std::vector<std::pair<std::string, std::int64_t>>& int_attrs = {});
  ~VolumeFileWriter();
  VolumeFileWriter(const VolumeFileWriter&) = delete;
  VolumeFileWriter& operator=(const VolumeFileWriter&) = delete;

  // Appends one volume of channels * height * width floats read at time t_us.
  void append(std::int64_t t_us, const float* volume);
  void finish();
  std::int64_t count() const { return count_; }

 private:
  void close_handles() noexcept;

  std::string path_, tmp_path_;
  std::unique_ptr<TempFile> tmp_;
  int channels_, height_, width_;
  std::int64_t count_ = 0;
  std::int64_t file_ = -1, volumes_ = -1, times_ = -1;  // hid_t, kept opaque here
  bool finished_ = false;
};

}  // namespace yelan::camera
