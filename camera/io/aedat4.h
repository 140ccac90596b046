// AEDAT 4.0 (iniVation DV): `#!AER-DAT4.0\r\n`, a size-prefixed IOHeader flatbuffer
// (compression, dataTablePosition, infoNode XML naming the streams), then packets
// {int32 stream id, int32 size, payload}; payloads are LZ4-frame/Zstd compressed
// size-prefixed flatbuffers. Only the first event stream (EVTS) is read; frame, IMU and
// trigger packets are skipped.
#pragma once
#include <map>
#include <memory>
#include <string>

#include "camera/io/event_reader.h"

namespace yelan::camera {

struct Aedat4Stream {
  std::string type;  // typeIdentifier: EVTS, FRME, IMUS, TRIG, ...
  int width = 0, height = 0;
};

// Stream id -> stream, from the infoNode XML of the header.
std::map<int, Aedat4Stream> parse_aedat4_info_node(const std::string& xml);

std::unique_ptr<EventReader> open_aedat4(const std::string& path);

inline constexpr char kAedat4Magic[] = "#!AER-DAT4.0\r\n";

}  // namespace yelan::camera
