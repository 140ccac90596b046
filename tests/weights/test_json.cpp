#include <catch2/catch.hpp>

#include <string>

#include "weights_tools/json.h"

using yelan::weights::Json;
using yelan::weights::JsonError;

TEST_CASE("json: values, escapes and a compact dump that keeps key order and number text", "[weights][json]") {
  const std::string text =
      R"( {"z": [1, 2.5e3, -0.0, true, false, null], "a": {"s": "q\"b\\n\n\u00e9\ud83d\ude00"}} )";
  const Json j = Json::parse(text);
  REQUIRE(j.is_object());
  REQUIRE(j.members().size() == 2);
  CHECK(j.members()[0].first == "z");  // original order, not sorted
  const Json& z = *j.find("z");
  REQUIRE(z.items().size() == 6);
  CHECK(z.items()[1].number() == 2500.0);
  CHECK(z.items()[3].boolean());
  CHECK(z.items()[5].kind() == Json::Kind::null);
  CHECK(j.find("a")->find("s")->string() == "q\"b\\n\n\xC3\xA9\xF0\x9F\x98\x80");
  CHECK(j.find("missing") == nullptr);
  CHECK(j.dump() == R"({"z":[1,2.5e3,-0.0,true,false,null],"a":{"s":"q\"b\\n\n)" "\xC3\xA9\xF0\x9F\x98\x80" R"("}})");
  CHECK(Json::parse(j.dump()).dump() == j.dump());
}

TEST_CASE("json: malformed text names the byte offset and the problem", "[weights][json]") {
  struct Case { std::string text, message; };
  for (const Case& c : std::vector<Case>{
           {"", "offset 0: unexpected end of text"},
           {R"({"a":})", "offset 5: unexpected character '}'"},
           {"[1,]", "offset 3: unexpected character ']'"},
           {R"({"a":1} x)", "offset 8: unexpected text after the JSON value"},
           {R"("abc)", "offset 4: unterminated string"},
           {R"({"a" 1})", "offset 5: expected ':'"},
           {"{1:2}", "offset 1: expected a string key"},
           {"1e999", "offset 0: number out of range"},
           {"-", "offset 1: malformed number"},
           {"[-012]", "offset 2: leading zero in a number"},
           {"1.", "offset 2: malformed number"},
           {R"("\q")", "offset 2: bad escape '\\q'"},
           {std::string(100, '['), "offset 65: nesting deeper than 64"},
       }) {
    INFO(c.text);
    try {
      Json::parse(c.text);
      FAIL("no error");
    } catch (const JsonError& e) {
      CHECK(std::string(e.what()) == c.message);
    }
  }
}
