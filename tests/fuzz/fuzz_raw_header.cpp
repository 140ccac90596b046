// Prophesee RAW with the header fuzzed too: header parsing, format dispatch, then decoding.
#include "camera/io/prophesee_raw.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".raw", yelan::camera::open_prophesee_raw);
}
