// Labelled recordings (camera/sim/recording_reader.h): the info, the masks and the events of
// an input laid out as `yelan sim` writes them. libhdf5 reads it in a child process first.
#include "camera/io/untrusted.h"
#include "camera/sim/recording_reader.h"
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  yelan::camera::forget_vetted_files();
  const std::string& path = yelan::fuzz::scratch_path(".yelan.h5");
  yelan::fuzz::write_input(path, data, size);
  try {
    const auto info = yelan::camera::sim::read_recording_info(path);
    const auto masks = yelan::camera::sim::read_recording_masks(path, 0, 4);
    if (masks.size() % (std::size_t(info.camera.width) * std::size_t(info.camera.height)) != 0) __builtin_trap();
    auto events = yelan::camera::open_event_file(path);
    yelan::fuzz::drain(*events);
  } catch (const yelan::camera::FormatError&) {
  }
  return 0;
}
