#include <cstring>

#include "camera/io/aedat4.h"
#include "camera/io/aedat_legacy.h"
#include "camera/io/byte_source.h"
#include "camera/io/readers.h"
#include "camera/io/untrusted.h"

namespace yelan::camera {
namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

bool starts(const unsigned char* b, std::size_t n, const char* magic) {
  const std::size_t m = std::strlen(magic);
  return n >= m && std::memcmp(b, magic, m) == 0;
}

}  // namespace

std::string detect_event_format(const std::string& path) {
  ByteSource src(path);
  unsigned char head[64] = {};
  const std::size_t n = src.read_some(head, sizeof head);
  if (starts(head, n, "#!AER-DAT4.0")) return "aedat4";
  if (starts(head, n, "#!AER-DAT2.0") || starts(head, n, "#!AER-DAT3.1")) return "aedat-old";
  if (starts(head, n, "\x89HDF\r\n\x1a\n")) return "hdf5";
  if (starts(head, n, "\x93NUMPY")) return "npy";
  if (starts(head, n, "% ") || starts(head, n, "%\n")) return "prophesee-raw";
  if (ends_with(path, ".raw")) return "prophesee-raw";
  if (ends_with(path, ".txt") || ends_with(path, ".csv")) return "text";
  if (ends_with(path, ".aedat4")) return "aedat4";
  if (ends_with(path, ".h5") || ends_with(path, ".hdf5")) return "hdf5";
  // Text starts with a digit, a sign, a comment or blank space.
  if (n > 0 && (std::strchr("0123456789.-# \t\r\n", head[0]) != nullptr)) {
    bool printable = true;
    for (std::size_t i = 0; i < n; ++i)
      if (head[i] < 9 || (head[i] > 13 && head[i] < 32) || head[i] > 126) printable = false;
    if (printable) return "text";
  }
  return "";
}

std::unique_ptr<EventReader> open_event_file(const std::string& path) {
  const std::string f = detect_event_format(path);
  if (f == "aedat4") return open_aedat4(path);
  if (f == "prophesee-raw") return open_prophesee_raw(path);
  if (f == "text") return open_text_events(path);
  if (f == "hdf5") {
    vet_in_child(path, [&] {
      auto r = open_hdf5_events(path);
      std::vector<Event> v;
      while (r->read(v, 1 << 20)) v.clear();
    });
    return open_hdf5_events(path);
  }
  if (f == "aedat-old") return open_aedat_legacy(path);
  if (f == "npy") return open_npy_events(path);
  throw FormatError(path, 0, "unknown event file format (no known magic bytes or extension)");
}

}  // namespace yelan::camera
