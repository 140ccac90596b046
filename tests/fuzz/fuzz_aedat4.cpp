// AEDAT 4.0: magic, IOHeader flatbuffer, info XML, packets, LZ4/Zstd, event flatbuffers.
#include "camera/io/aedat4.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".aedat4", yelan::camera::open_aedat4);
}
