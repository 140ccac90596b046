// `yelan info` and `yelan convert` in-process, as a user's shell would see them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <sstream>

#include "engine/cli/cli.h"
#include "io_test_util.h"
#include "test_util.h"
#include "cli_util.h"

using namespace yelan::test;

namespace {
using Run = yelan::test::CliResult;
Run cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
bool has(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }
}  // namespace

TEST_CASE("info --json on the three real files", "[io][cli][real]") {
  struct Case {
    const char* rel;
    std::vector<std::string> want;
  };
  for (const Case& c : std::vector<Case>{
           {"events/aestream_davis.aedat4",
            {"\"format\": \"aedat4\"", "\"width\": 346", "\"height\": 260", "\"events\": 117667",
             "\"on_events\": 72363", "\"t_first_us\": 1633953690975950", "\"t_last_us\": 1633953691105949",
             "\"duration_us\": 129999", "\"x_max\": 345", "\"y_max\": 259"}},
           {"events/evt3_sample.raw",
            {"\"format\": \"evt3\"", "\"width\": 1280", "\"height\": 720", "\"events\": 219596",
             "\"on_events\": 115532", "\"t_first_us\": 11718656", "\"t_last_us\": 11727457", "\"x_max\": 1279",
             "\"y_max\": 719"}},
           {"events/evt2_sample.raw",
            {"\"format\": \"evt2\"", "\"width\": 640", "\"height\": 480", "\"events\": 539481",
             "\"on_events\": 367855", "\"t_first_us\": 1317888", "\"t_last_us\": 1367888",
             "\"duration_us\": 50000", "\"x_max\": 599", "\"y_max\": 475"}}}) {
    Run r = cli({"info", shared_data_or_skip(c.rel), "--json"});
    INFO(r.out << r.err);
    CHECK(r.code == 0);
    CHECK(r.err.empty());
    CHECK(r.out.front() == '{');
    CHECK(r.out.substr(r.out.size() - 2) == "}\n");
    CHECK(std::count(r.out.begin(), r.out.end(), '\n') == 1);
    for (const std::string& w : c.want) CHECK(has(r.out, w));
  }
}

TEST_CASE("info in words names format, sensor, count, span and balance", "[io][cli][real]") {
  Run r = cli({"info", shared_data_or_skip("events/evt2_sample.raw")});
  CHECK(r.code == 0);
  CHECK(has(r.out, "format:    evt2"));
  CHECK(has(r.out, "sensor:    640x480"));
  CHECK(has(r.out, "events:    539481 (ON 367855 = 68.2%, OFF 171626)"));
  CHECK(has(r.out, "time:      1317888 .. 1367888 us (50.000 ms)"));
  CHECK(has(r.out, "rate:      10.790 Mev/s"));
}

TEST_CASE("convert writes every output format and info reads them back", "[io][cli][real]") {
  const std::string src = shared_data_or_skip("events/aestream_davis.aedat4");
  ScratchDir dir("cliconv");
  for (const char* name : {"o.yelan.h5", "o.aedat4", "o.txt"}) {
    const std::string out = dir.file(name);
    Run r = cli({"convert", src, out});
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(has(r.err, "117667 events"));  // not a TTY: one summary line
    CHECK(r.err.find('\r') == std::string::npos);
    Run i = cli({"info", out, "--json"});
    CHECK(i.code == 0);
    CHECK(has(i.out, "\"events\": 117667"));
    CHECK(has(i.out, "\"on_events\": 72363"));
    CHECK(has(i.out, "\"t_first_us\": 1633953690975950"));
    CHECK(has(i.out, "\"width\": 346"));
  }
}

TEST_CASE("info and convert: bad usage and bad input exit 2", "[io][cli]") {
  ScratchDir dir("clibad");
  const std::string junk = dir.file("junk.aedat4");
  write_text(junk, "#!AER-DAT4.0\r\n\x05");
  Run r = cli({"info", junk});
  CHECK(r.code == 2);
  CHECK(r.err == "yelan: error: " + junk + ": offset 14: truncated header size: needs 4 bytes, file ends after 1\n");
  CHECK(cli({"info"}).code == 2);
  CHECK(cli({"info", junk, "extra"}).code == 2);
  CHECK(cli({"info", junk, "--xml"}).code == 2);
  CHECK(cli({"convert", junk}).code == 2);
  Run c = cli({"convert", junk, dir.file("out.png")});
  CHECK(c.code == 2);
  CHECK(has(c.err, "cannot tell the output format"));
  Run m = cli({"info", dir.file("missing.raw")});
  CHECK(m.code == 2);
  CHECK(has(m.err, "missing.raw: offset 0: cannot open"));
  Run bad = cli({"convert", junk, dir.file("out.txt")});
  CHECK(bad.code == 2);
  CHECK_FALSE(std::filesystem::exists(dir.file("out.txt")));
}

TEST_CASE("info --camera picks one DHP19 camera of an AEDAT 2.0 file", "[io][cli][dhp19]") {
  ScratchDir dir("clicam");
  const std::string p = dir.file("dhp19.aedat");
  auto b = raw_header("#!AER-DAT2.0\r\n# HardwareInterface: DAVIS346\r\n");
  auto event = [&](unsigned x, unsigned y, unsigned pol, unsigned cam, std::uint32_t ts) {
    const std::uint32_t a = (y << 22) | (x << 12) | (pol << 11) | cam;
    for (int i = 3; i >= 0; --i) b.push_back(static_cast<unsigned char>(a >> (8 * i)));
    for (int i = 3; i >= 0; --i) b.push_back(static_cast<unsigned char>(ts >> (8 * i)));
  };
  event(1, 2, 1, 0, 10);
  event(3, 4, 0, 2, 11);
  event(5, 6, 1, 2, 12);
  write_bytes(p, b);
  Run all = cli({"info", p, "--json"});
  CHECK(has(all.out, "\"events\": 3"));
  Run cam2 = cli({"info", p, "--json", "--camera", "2"});
  CHECK(cam2.code == 0);
  CHECK(has(cam2.out, "\"format\": \"aedat2\""));
  CHECK(has(cam2.out, "\"events\": 2"));
  CHECK(has(cam2.out, "\"t_first_us\": 11"));
  CHECK(cli({"info", p, "--camera", "16"}).code == 2);
  const std::string txt = dir.file("e.txt");
  write_text(txt, "# t_us x y p\n1 2 3 1\n");
  Run wrong = cli({"info", txt, "--camera", "1"});
  CHECK(wrong.code == 2);
  CHECK(has(wrong.err, "applies to AEDAT 2.0 files"));
}
