// Prophesee RAW files (EVT 2.0, EVT 2.1, EVT 3.0): an ASCII header of `% key value` lines,
// then little-endian words. Exposed for tests and fuzz targets; users call open_event_file.
#pragma once
#include <memory>
#include <string>

#include "camera/io/event_reader.h"

namespace yelan::camera {

struct RawHeader {
  std::string evt;            // "2.0", "2.1" or "3.0"; empty when the header does not say
  int width = 0, height = 0;  // from `% geometry WxH`, `% format ...;width=;height=` or the plugin
  std::uint64_t data_offset = 0;  // first byte after the header
};

// Parses the header at the start of the file (it may be empty).
RawHeader parse_raw_header(const std::string& path);

std::unique_ptr<EventReader> open_prophesee_raw(const std::string& path);  // also in readers.h

}  // namespace yelan::camera
