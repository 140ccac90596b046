// EVT 3.0 decoder: the input is the word stream after a fixed header.
#include "camera/io/prophesee_raw.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".raw", yelan::camera::open_prophesee_raw, "% evt 3.0\n% geometry 1280x720\n");
}
