// The little of FlatBuffers that AEDAT 4.0 needs, by hand: reading tables, scalars, strings
// and vectors with every offset bounds-checked (a bad offset throws FlatError, never reads
// outside the buffer), and writing the few fixed layouts our AEDAT writer emits.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace yelan::camera::flat {

struct FlatError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Table {
  const unsigned char* buf = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;      // table start
  std::size_t vtable = 0;   // vtable start
  std::size_t vt_size = 0;  // vtable bytes
  std::size_t tbl_size = 0;
};

// The root table of a buffer that starts at its root offset (no size prefix).
Table root(const unsigned char* buf, std::size_t size);
// The table a uoffset at `at` points to.
Table table_at(const unsigned char* buf, std::size_t size, std::size_t at);
// Absolute position of a field whose value has `bytes` bytes, or nullopt when absent.
std::optional<std::size_t> field(const Table& t, int slot, std::size_t bytes);
std::int64_t field_i64(const Table& t, int slot, std::int64_t fallback);
std::int32_t field_i32(const Table& t, int slot, std::int32_t fallback);
std::optional<std::string> field_string(const Table& t, int slot, std::size_t max_len);
// A vector field: position of its first element and element count (nullopt when absent).
std::optional<std::pair<std::size_t, std::size_t>> field_vector(const Table& t, int slot,
                                                                 std::size_t elem_bytes);

}  // namespace yelan::camera::flat
