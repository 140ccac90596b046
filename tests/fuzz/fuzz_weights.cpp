// Weights files (weights_tools/weights_file.h): header, config, every tensor and its
// checksum. libhdf5 reads the input in a child process first.
#include "camera/io/untrusted.h"
#include "fuzz_common.h"
#include "weights_tools/weights_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  yelan::camera::forget_vetted_files();
  const std::string& path = yelan::fuzz::scratch_path(".weights.h5");
  yelan::fuzz::write_input(path, data, size);
  try {
    const yelan::weights::Weights w = yelan::weights::load_weights(path);
    for (const auto& [group, tensors] : w.groups)
      for (const auto& [name, t] : tensors)
        if (std::int64_t(t.data.size()) != yelan::weights::element_count(t.shape)) __builtin_trap();
  } catch (const yelan::weights::WeightsError&) {
  }
  return 0;
}
