// AEDAT 2.0 and 3.1: `#` header lines, big-endian address/timestamp pairs or 3.1 packets.
#include "camera/io/aedat_legacy.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".aedat", [](const std::string& p) {
    return yelan::camera::open_aedat_legacy(p, -1);
  });
}
