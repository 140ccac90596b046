#include "camera/io/flatbuf.h"

#include "camera/io/byte_source.h"

namespace yelan::camera::flat {
namespace {

void need(std::size_t size, std::size_t at, std::size_t bytes, const char* what) {
  if (at > size || bytes > size - at)
    throw FlatError(std::string(what) + " at flatbuffer byte " + std::to_string(at) + " lies outside its " +
                    std::to_string(size) + " bytes");
}

}  // namespace

Table table_at(const unsigned char* buf, std::size_t size, std::size_t at) {
  need(size, at, 4, "offset");
  const std::uint64_t target = at + static_cast<std::uint64_t>(load_le<std::uint32_t>(buf + at));
  need(size, target, 4, "table");
  Table t{buf, size, static_cast<std::size_t>(target), 0, 0, 0};
  const std::int64_t vt = static_cast<std::int64_t>(t.pos) - load_le<std::int32_t>(buf + t.pos);
  if (vt < 0) throw FlatError("vtable before the start of the flatbuffer");
  t.vtable = static_cast<std::size_t>(vt);
  need(size, t.vtable, 4, "vtable");
  t.vt_size = load_le<std::uint16_t>(buf + t.vtable);
  t.tbl_size = load_le<std::uint16_t>(buf + t.vtable + 2);
  if (t.vt_size < 4 || t.vt_size % 2) throw FlatError("malformed vtable size " + std::to_string(t.vt_size));
  need(size, t.vtable, t.vt_size, "vtable");
  need(size, t.pos, t.tbl_size, "table");
  return t;
}

Table root(const unsigned char* buf, std::size_t size) { return table_at(buf, size, 0); }

std::optional<std::size_t> field(const Table& t, int slot, std::size_t bytes) {
  const std::size_t entry = 4 + 2 * static_cast<std::size_t>(slot);
  if (entry + 2 > t.vt_size) return std::nullopt;
  const std::size_t off = load_le<std::uint16_t>(t.buf + t.vtable + entry);
  if (off == 0) return std::nullopt;
  if (off + bytes > t.tbl_size) throw FlatError("field " + std::to_string(slot) + " runs past its table");
  return t.pos + off;
}

std::int64_t field_i64(const Table& t, int slot, std::int64_t fallback) {
  auto at = field(t, slot, 8);
  return at ? load_le<std::int64_t>(t.buf + *at) : fallback;
}

std::int32_t field_i32(const Table& t, int slot, std::int32_t fallback) {
  auto at = field(t, slot, 4);
  return at ? load_le<std::int32_t>(t.buf + *at) : fallback;
}

static std::optional<std::pair<std::size_t, std::size_t>> vector_at(const Table& t, std::size_t at,
                                                                    std::size_t elem_bytes) {
  const std::uint64_t start = at + static_cast<std::uint64_t>(load_le<std::uint32_t>(t.buf + at));
  need(t.size, start, 4, "vector length");
  const std::uint64_t n = load_le<std::uint32_t>(t.buf + start);
  if (elem_bytes && n > (t.size - start - 4) / elem_bytes)
    throw FlatError("vector of " + std::to_string(n) + " elements does not fit in the flatbuffer");
  return std::make_pair(static_cast<std::size_t>(start + 4), static_cast<std::size_t>(n));
}

std::optional<std::string> field_string(const Table& t, int slot, std::size_t max_len) {
  auto at = field(t, slot, 4);
  if (!at) return std::nullopt;
  auto v = vector_at(t, *at, 1);
  if (v->second > max_len) throw FlatError("string longer than " + std::to_string(max_len) + " bytes");
  return std::string(reinterpret_cast<const char*>(t.buf + v->first), v->second);
}

std::optional<std::pair<std::size_t, std::size_t>> field_vector(const Table& t, int slot,
                                                                 std::size_t elem_bytes) {
  auto at = field(t, slot, 4);
  if (!at) return std::nullopt;
  return vector_at(t, *at, elem_bytes);
}

}  // namespace yelan::camera::flat
