#include "weights_tools/parse_json.h"

#include <utility>

namespace yelan::weights {
namespace {

constexpr int kMaxDepth = 64;
constexpr auto npos = std::string::npos;

// The first byte of `t` outside string literals where stop(i) holds, or npos.
template <class Stop>
std::size_t find_outside_strings(const std::string& t, Stop stop) {
  bool in_string = false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (in_string) {
      if (t[i] == '\\') ++i;
      else if (t[i] == '"') in_string = false;
    } else if (t[i] == '"') {
      in_string = true;
    } else if (stop(i)) {
      return i;
    }
  }
  return npos;
}

// nlohmann says "[json.exception.parse_error.101] parse error at line L, column C: syntax
// error while parsing CONTEXT - DETAIL[; last read: 'TOKEN'][; expected WHAT]". Ours is the
// DETAIL, without the token (it can be as long as the file), in our words where we had some.
std::string problem_of(const std::string& what) {
  static const std::pair<const char*, const char*> kOurWords[] = {
      {"parsing object key -", "expected a string key"},  // "{" ends here too
      {"parsing object separator -", "expected ':'"},
      {"unexpected end of input", "unexpected end of text"},  // before the next, which it holds
      {"expected end of input", "unexpected text after the JSON value"},
      {"missing closing quote", "unterminated string"},
  };
  for (const auto& [theirs, ours] : kOurWords)
    if (what.find(theirs) != npos) return ours;
  const std::size_t dash = what.find(" - ");
  std::string p = dash == npos ? what : what.substr(dash + 3);
  if (const std::size_t token = p.find("; last read: '"); token != npos) {
    const std::size_t expected = p.rfind("'; expected ");
    p.erase(token, expected == npos || expected < token ? npos : expected + 1 - token);
  }
  return p;
}

bool in_number(char c) { return (c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == '+' || c == '-'; }

}  // namespace

nlohmann::ordered_json parse_json(const std::string& text) {
  int depth = 0;
  const std::size_t deep = find_outside_strings(text, [&](std::size_t i) {
    if (text[i] == '[' || text[i] == '{') return ++depth > kMaxDepth;
    if (text[i] == ']' || text[i] == '}') --depth;
    return false;
  });
  if (deep != npos) throw JsonError(deep, "nesting deeper than " + std::to_string(kMaxDepth));
  try {
    return nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw JsonError(e.byte ? e.byte - 1 : 0, problem_of(e.what()));  // e.byte counts from 1
  } catch (const nlohmann::json::out_of_range& e) {
    // "number overflow parsing '1e999'", without a position: the text before it was valid,
    // so the first such number token outside the strings is the one.
    const std::string what = e.what();
    const std::size_t q = what.find('\'');
    const std::string token = q == npos ? std::string() : what.substr(q + 1, what.rfind('\'') - q - 1);
    const std::size_t at = token.empty() ? npos : find_outside_strings(text, [&](std::size_t i) {
      return text.compare(i, token.size(), token) == 0 && (i == 0 || !in_number(text[i - 1]));
    });
    throw JsonError(at == npos ? 0 : at, "number out of range");
  }
}

}  // namespace yelan::weights
