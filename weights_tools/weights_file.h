// Our HDF5 weights file: root attributes format="yelan-weights", version=1, config=<JSON>;
// groups /mask and /pose holding one float32 dataset per PyTorch state_dict entry, named
// by its key, in PyTorch's layout (README.md lists the names). Reading checks everything
// and names the file and the problem; writing is atomic and free of time stamps.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace yelan::weights {

inline constexpr const char* kFormat = "yelan-weights";
inline constexpr std::int64_t kVersion = 1;
// The two networks, in the order files list them.
inline const std::vector<std::string>& group_names() {
  static const std::vector<std::string> names = {"mask", "pose"};
  return names;
}
// A tensor larger than this (4 GiB of float32) is taken as a corrupt header, not as data.
inline constexpr std::int64_t kMaxElements = std::int64_t(1) << 30;

// Bad input (a foreign, damaged or mismatched file). The CLI maps it to exit code 2.
struct WeightsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using Shape = std::vector<std::int64_t>;
std::string shape_text(const Shape& s);  // "[64, 6, 7, 7]", "[]" for a scalar
std::int64_t element_count(const Shape& s);
// False for BatchNorm buffers (running_mean, running_var, num_batches_tracked).
bool is_parameter(const std::string& name);

struct TensorInfo {
  std::string group, name;
  Shape shape;
};

// An open weights file whose header and tensor list were checked on opening. Data is read
// one tensor at a time, so comparing two files never holds either whole in memory.
class WeightsReader {
 public:
  explicit WeightsReader(const std::string& path);
  ~WeightsReader();
  WeightsReader(const WeightsReader&) = delete;
  WeightsReader& operator=(const WeightsReader&) = delete;

  const std::string& path() const { return path_; }
  std::int64_t version() const { return version_; }
  const std::string& config_json() const { return config_json_; }
  // Sorted by name.
  const std::vector<TensorInfo>& tensors(const std::string& group) const;
  const TensorInfo* find(const std::string& group, const std::string& name) const;
  std::vector<float> read(const TensorInfo& t) const;

 private:
  struct File;
  std::unique_ptr<File> file_;
  std::string path_;
  std::int64_t version_ = 0;
  std::string config_json_;
  std::map<std::string, std::vector<TensorInfo>> tensors_;
};

struct Tensor {
  Shape shape;
  std::vector<float> data;
};

struct Weights {
  std::string config_json;
  std::map<std::string, std::map<std::string, Tensor>> groups;  // group -> key -> tensor
};

Weights load_weights(const std::string& path);
// Writes a TempFile beside `path` and renames it over `path`; nothing is left behind on failure.
void save_weights(const std::string& path, const Weights& w);

}  // namespace yelan::weights
