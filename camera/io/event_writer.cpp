#include "camera/io/event_writer.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace yelan::camera {

namespace {
bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
}  // namespace

std::string writer_format_for(const std::string& path) {
  if (ends_with(path, ".yelan.h5") || ends_with(path, ".h5") || ends_with(path, ".hdf5")) return "yelan-h5";
  if (ends_with(path, ".aedat4")) return "aedat4";
  if (ends_with(path, ".txt")) return "text";
  return "";
}

std::unique_ptr<EventWriter> open_event_writer(const std::string& path, const StreamInfo& info) {
  const std::string f = writer_format_for(path);
  if (f == "yelan-h5") return open_yelan_h5_writer(path, info);
  if (f == "aedat4") return open_aedat4_writer(path, info);
  if (f == "text") return open_text_writer(path, info);
  throw std::invalid_argument("cannot tell the output format of '" + path +
                              "' (use .yelan.h5, .h5, .aedat4 or .txt)");
}

}  // namespace yelan::camera
