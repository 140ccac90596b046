// JSON text in (nlohmann, ordered so that a config keeps its key order when written back),
// errors out in our style: JsonError "offset N: problem", N the byte where reading stopped.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace yelan::weights {

struct JsonError : std::runtime_error {
  JsonError(std::size_t offset, const std::string& problem)
      : std::runtime_error("offset " + std::to_string(offset) + ": " + problem), offset(offset) {}
  std::size_t offset;
};

// Throws JsonError on malformed text, on trailing garbage, on a number beyond a double and on
// containers nested deeper than 64 (what we write is 3 deep; dump() and our walks recurse).
nlohmann::ordered_json parse_json(const std::string& text);

}  // namespace yelan::weights
