// A small JSON reader and writer helper: enough for our configs and manifests, with errors
// that give the byte offset. Objects keep their key order.
#pragma once
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace yelan::weights {

struct JsonError : std::runtime_error {
  JsonError(std::size_t offset, const std::string& problem)
      : std::runtime_error("offset " + std::to_string(offset) + ": " + problem), offset(offset) {}
  std::size_t offset;
};

class Json {
 public:
  enum class Kind { null, boolean, number, string, array, object };

  Kind kind() const { return kind_; }
  bool is_object() const { return kind_ == Kind::object; }
  bool is_array() const { return kind_ == Kind::array; }
  bool is_string() const { return kind_ == Kind::string; }
  bool is_number() const { return kind_ == Kind::number; }

  double number() const { return number_; }
  const std::string& string() const { return text_; }  // the string's value
  bool boolean() const { return boolean_; }
  const std::vector<Json>& items() const { return items_; }
  const std::vector<std::pair<std::string, Json>>& members() const { return members_; }
  // nullptr when absent or when this is not an object.
  const Json* find(const std::string& key) const;

  // Compact JSON text of this value (keys in their original order).
  std::string dump() const;

  // Throws JsonError on malformed text, on trailing garbage and on nesting deeper than 64.
  static Json parse(const std::string& text);

 private:
  friend class JsonParser;
  Kind kind_ = Kind::null;
  bool boolean_ = false;
  double number_ = 0;
  std::string text_;  // string value, or a number's source text (kept exact for dump)
  std::vector<Json> items_;
  std::vector<std::pair<std::string, Json>> members_;
};

// `s` as a JSON string literal, quotes included.
std::string json_quote(const std::string& s);

}  // namespace yelan::weights
