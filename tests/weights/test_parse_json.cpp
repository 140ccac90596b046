#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "weights_tools/parse_json.h"

using yelan::weights::JsonError;
using yelan::weights::parse_json;

TEST_CASE("parse_json: keys stay in their order, so a config written back reads the same", "[weights][json]") {
  const std::string text = R"( {"z": [1, 2.5, -0.0, true, false, null], "a": {"s": "q\"b\\n\n\u00e9"}} )";
  CHECK(parse_json(text).dump() == R"({"z":[1,2.5,-0.0,true,false,null],"a":{"s":"q\"b\\n\n)" "\xC3\xA9" R"("}})");
  // 64 levels are fine, and brackets inside strings (after an escaped quote too) are no nesting.
  CHECK(parse_json(std::string(64, '[') + std::string(64, ']')).size() == 1);
  CHECK(parse_json("\"\\\"" + std::string(100, '[') + "\"").get<std::string>() == "\"" + std::string(100, '['));
}

TEST_CASE("parse_json: malformed text names the byte offset and the problem", "[weights][json]") {
  struct Case { std::string text, message; bool whole = true; };
  for (const Case& c : std::vector<Case>{
           {"", "offset 0: unexpected end of text"},
           {"{\"format\": ", "offset 11: unexpected end of text"},
           {R"({"a":1} x)", "offset 8: unexpected text after the JSON value"},
           {R"("abc)", "offset 4: unterminated string"},
           {R"({"a" 1})", "offset 5: expected ':'"},
           {"{1:2}", "offset 1: expected a string key"},
           {"{", "offset 1: expected a string key"},
           {R"({"s":"1e999","n":[1e999]})", "offset 18: number out of range"},
           {std::string(100, '['), "offset 64: nesting deeper than 64"},
           // nlohmann's own words where we have none (their start), without the token it read
           {R"({"a":})", "offset 5: unexpected '}'", false},
           {"[1,]", "offset 3: unexpected ']'", false},
           {"-", "offset 1: invalid number", false},
           {R"({"a":1e5x})", "offset 8: invalid literal", false},
           {R"("\q")", "offset 2: invalid string", false},
       }) {
    INFO(c.text);
    try {
      parse_json(c.text);
      FAIL("no error");
    } catch (const JsonError& e) {
      const std::string what = e.what();
      if (c.whole) CHECK(what == c.message);
      else CHECK(what.rfind(c.message, 0) == 0);
      CHECK(what.find("last read") == std::string::npos);
      CHECK(what.find("json.exception") == std::string::npos);
      CHECK("offset " + std::to_string(e.offset) + ":" == c.message.substr(0, c.message.find(':') + 1));
    }
  }
}
