// HDF5 events (ours, DSEC, v2e), opened as any event file is: libhdf5 first reads the
// input in a child process (camera/io/untrusted.h), so its own crashes on crafted files
// come back as a FormatError; what remains to find is ours.
#include "camera/io/untrusted.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  yelan::camera::forget_vetted_files();
  return yelan::fuzz::run_one(data, size, ".h5", yelan::camera::open_event_file);
}
