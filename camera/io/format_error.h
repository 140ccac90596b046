// The error every event-file reader throws for bad input: it names the file, the byte offset
// where the problem was found and the problem, so a user can look at the bytes themselves.
// The CLI maps it to exit code 2 (bad input).
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>

namespace yelan::camera {

class FormatError : public std::runtime_error {
 public:
  FormatError(std::string file, std::uint64_t offset, std::string problem);
  const std::string& file() const { return file_; }
  std::uint64_t offset() const { return offset_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  std::uint64_t offset_;
  std::string problem_;
};

}  // namespace yelan::camera
