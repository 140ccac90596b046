// HDF5 events (ours, DSEC, v2e). Much of what this reaches is libhdf5 itself.
#include "camera/io/readers.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return yelan::fuzz::run_one(data, size, ".h5", yelan::camera::open_hdf5_events);
}
