// AEDAT 2.0 (jAER: big-endian {int32 address, int32 timestamp} pairs after `#` header lines;
// DAVIS address layout: y bits 30..22, x bits 21..12, polarity bit 11; bit 31 set = APS/IMU)
// and AEDAT 3.1 (little-endian packets with a 28-byte header; polarity events of type 1).
// DHP19 records four DAVIS346 cameras in one AEDAT 2.0 stream, told apart by address & 0xF.
#pragma once
#include <memory>
#include <string>

#include "camera/io/event_reader.h"

namespace yelan::camera {

// camera: keep only DVS events whose address & 0xF equals it (DHP19); -1 keeps all.
std::unique_ptr<EventReader> open_aedat_legacy(const std::string& path, int camera = -1);

}  // namespace yelan::camera
