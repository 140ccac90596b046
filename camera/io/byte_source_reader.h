// The base of the event readers that stream a file through a ByteSource (every format but
// HDF5): the source, and the position and size that progress bars and `info` report.
#pragma once
#include <cstdint>
#include <string>

#include "camera/io/byte_source.h"
#include "camera/io/event_reader.h"

namespace yelan::camera {

class ByteSourceReader : public EventReader {
 public:
  std::uint64_t position() const override { return src_.offset(); }
  std::uint64_t file_size() const override { return src_.size(); }

 protected:
  explicit ByteSourceReader(const std::string& path) : EventReader(path), src_(path) {}
  ByteSource src_;
};

}  // namespace yelan::camera
