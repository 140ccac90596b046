// Text events (`t x y p` lines, seconds or `# t_us` microseconds).
#include "camera/io/readers.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".txt", yelan::camera::open_text_events);
}
