// A read-only file with a cursor, read in bounded pieces. Every short read or seek past the
// end becomes a FormatError that names the file and the offset, so decoders need no checks
// of their own beyond "is there enough left".
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace yelan::camera {

class ByteSource {
 public:
  explicit ByteSource(std::string path);
  const std::string& path() const { return path_; }
  std::uint64_t size() const { return size_; }
  std::uint64_t offset() const { return offset_; }
  std::uint64_t remaining() const { return size_ - offset_; }
  // Reads up to n bytes; fewer only at the end of the file.
  std::size_t read_some(void* dst, std::size_t n);
  // Reads exactly n bytes or throws "truncated <what>".
  void read_exact(void* dst, std::size_t n, const std::string& what);
  void seek(std::uint64_t offset);
  [[noreturn]] void fail(const std::string& problem) const;
  [[noreturn]] void fail_at(std::uint64_t offset, const std::string& problem) const;

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string path_;
  std::unique_ptr<std::FILE, Closer> file_;
  std::uint64_t size_ = 0, offset_ = 0;
};

// Little-endian loads from a byte buffer (all formats here are little-endian).
template <typename T>
inline T load_le(const unsigned char* p) {
  T v{};
  for (std::size_t i = 0; i < sizeof(T); ++i)
    v = static_cast<T>(v | static_cast<T>(static_cast<std::uint64_t>(p[i]) << (8 * i)));
  return v;
}

}  // namespace yelan::camera
