#include "camera/io/byte_source.h"

#include <cerrno>
#include <cstring>

#include "camera/io/format_error.h"

namespace yelan::camera {

ByteSource::ByteSource(std::string path) : path_(std::move(path)) {
  file_.reset(std::fopen(path_.c_str(), "rb"));
  if (!file_) throw FormatError(path_, 0, std::string("cannot open: ") + std::strerror(errno));
  if (std::fseek(file_.get(), 0, SEEK_END) != 0) fail("cannot seek (not a regular file?)");
  long end = std::ftell(file_.get());
  if (end < 0) fail("cannot tell the file size (not a regular file?)");
  size_ = static_cast<std::uint64_t>(end);
  seek(0);
}

std::size_t ByteSource::read_some(void* dst, std::size_t n) {
  std::size_t got = n ? std::fread(dst, 1, n, file_.get()) : 0;
  if (got < n && std::ferror(file_.get())) fail(std::string("read error: ") + std::strerror(errno));
  offset_ += got;
  return got;
}

void ByteSource::read_exact(void* dst, std::size_t n, const std::string& what) {
  const std::uint64_t at = offset_;
  if (read_some(dst, n) != n)
    fail_at(at, "truncated " + what + ": needs " + std::to_string(n) + " bytes, file ends after " +
                    std::to_string(size_ - at));
}

void ByteSource::seek(std::uint64_t offset) {
  if (offset > size_)
    fail_at(offset, "seek past the end of the file (" + std::to_string(size_) + " bytes)");
  if (std::fseek(file_.get(), static_cast<long>(offset), SEEK_SET) != 0) fail_at(offset, "cannot seek");
  offset_ = offset;
}

void ByteSource::fail(const std::string& problem) const { throw FormatError(path_, offset_, problem); }

void ByteSource::fail_at(std::uint64_t offset, const std::string& problem) const {
  throw FormatError(path_, offset, problem);
}

}  // namespace yelan::camera
