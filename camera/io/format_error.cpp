#include "camera/io/format_error.h"

namespace yelan::camera {

FormatError::FormatError(std::string file, std::uint64_t offset, std::string problem)
    : std::runtime_error(file + ": offset " + std::to_string(offset) + ": " + problem),
      file_(std::move(file)),
      offset_(offset),
      problem_(std::move(problem)) {}

}  // namespace yelan::camera
