// NumPy .npy structured event arrays: preamble, Python-dict header, records.
#include "camera/io/readers.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".npy", yelan::camera::open_npy_events);
}
