// A small RAII layer over the HDF5 C API: every hid_t is owned by an H5Id that closes it
// (files, groups, datasets, dataspaces, types, property lists, attributes). Errors become
// H5Failure exceptions; HDF5's own error printing is switched off.
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace yelan::camera::h5 {

struct H5Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class H5Id {
 public:
  H5Id() = default;
  explicit H5Id(hid_t id) : id_(id) {}
  H5Id(H5Id&& o) noexcept : id_(o.id_) { o.id_ = H5I_INVALID_HID; }
  H5Id& operator=(H5Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      o.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  ~H5Id() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  void reset() noexcept;

 private:
  hid_t id_ = H5I_INVALID_HID;
};

// Throws H5Failure(what) when id < 0; otherwise owns it.
H5Id check(hid_t id, const std::string& what);
void check(herr_t status, const std::string& what);

void silence_errors();

H5Id open_file(const std::string& path);          // read-only
H5Id create_file(const std::string& path);        // truncates
bool exists(hid_t loc, const std::string& path);  // every link on the path
H5Id create_group(hid_t loc, const std::string& name);

// Creation properties without object time stamps, so equal data gives equal bytes.
H5Id untimed_dataset_props();

// A 1-D dataset of `type` that grows by appends, chunked and deflate-compressed.
H5Id create_growing_1d(hid_t loc, const std::string& name, hid_t type, hsize_t chunk);
void append_1d(hid_t dataset, hid_t mem_type, const void* data, hsize_t n);

// Bytes of one chunk of a chunked dataset (0 when not chunked). A corrupt file can claim
// chunks of any size, and HDF5 allocates a whole chunk to read one element of it.
std::uint64_t chunk_bytes(hid_t dataset);

// Throws H5Failure when a stored chunk holding rows [first, first+n) of a chunked dataset
// lies past the end of the file or claims more than max_bytes: HDF5 would allocate it whole.
void check_stored_chunks(hid_t dataset, hsize_t first, hsize_t n, std::uint64_t file_size,
                         std::uint64_t max_bytes);

// Whether the dataset holds integers (or, unless integers_only, floats) of at most 8 bytes:
// a corrupt file can declare an integer of 2 GB per element, and HDF5 allocates its
// conversion buffer from that size before reading one element.
bool holds_small_numbers(hid_t dataset, bool integers_only = false);
// Throws H5Failure naming the dataset unless holds_small_numbers(dataset).
void require_numeric(hid_t dataset, const std::string& name);

// Dataset shape (empty for a scalar).
std::vector<hsize_t> shape(hid_t dataset);
// Reads rows [first, first+n) of a 1-D dataset (or a column `col` of a 2-D one) as `mem_type`.
void read_rows(hid_t dataset, hid_t mem_type, hsize_t first, hsize_t n, void* out, int col = -1);

void write_attr_string(hid_t loc, const std::string& name, const std::string& value);
void write_attr_i64(hid_t loc, const std::string& name, std::int64_t value);
std::optional<std::string> read_attr_string(hid_t loc, const std::string& name);
std::optional<std::int64_t> read_attr_i64(hid_t loc, const std::string& name);
// A scalar dataset (DSEC's t_offset) read as int64.
std::optional<std::int64_t> read_scalar_i64(hid_t loc, const std::string& name);

}  // namespace yelan::camera::h5
