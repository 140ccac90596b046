// `yelan sim` through the CLI: byte-identical recordings per seed, `yelan info` on them,
// previews, grids with a manifest, and clear errors.
#include <algorithm>
#include <catch2/catch.hpp>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "camera/sim/dataset.h"
#include "cli_util.h"

using yelan::test::slurp;
using Result = yelan::test::CliResult;

namespace {
Result cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
bool has(const std::string& s, const std::string& w) { return yelan::test::contains(s, w); }
struct TempDir : yelan::test::CliTempDir {
  TempDir() : CliTempDir("sim-cli") {}
};
}  // namespace

TEST_CASE("yelan sim: the same arguments give the same bytes, and yelan info reads the result", "[cli][sim]") {
  TempDir d;
  const std::vector<std::string> args = {"sim", "--preset", "ben-dance3-front-high-static", "--seed", "4", "--duration",
                                         "60ms"};
  auto with_out = [&](const std::string& o, std::vector<std::string> extra = {}) {
    auto v = args;
    v.push_back("-o");
    v.push_back(o);
    v.insert(v.end(), extra.begin(), extra.end());
    return cli(v);
  };
  const Result a = with_out(d / "a.yelan.h5");
  INFO(a.err);
  REQUIRE(a.code == 0);
  CHECK(has(a.out, "labels"));
  REQUIRE(with_out(d / "b.yelan.h5", {"--threads", "1"}).code == 0);
  const std::string ba = slurp(d / "a.yelan.h5"), bb = slurp(d / "b.yelan.h5");
  CHECK(ba.size() > 10000);
  CHECK(ba == bb);
  auto v = args;
  v[4] = "5";
  v.push_back("-o");
  v.push_back(d / "c.yelan.h5");
  REQUIRE(cli(v).code == 0);
  CHECK(slurp(d / "c.yelan.h5") != ba);
  const Result info = cli({"info", "--json", d / "a.yelan.h5"});
  INFO(info.err);
  REQUIRE(info.code == 0);
  CHECK(has(info.out, "\"width\": 346"));
  CHECK(has(info.out, "\"height\": 260"));
  // Previews: frames and a contact sheet.
  const Result p = with_out(d / "p.yelan.h5", {"--preview", d / "prev", "--preview-every", "1"});
  REQUIRE(p.code == 0);
  CHECK(std::filesystem::exists(d / "prev/contact_sheet.png"));
  CHECK(std::filesystem::exists(d / "prev/frame_00020000.png"));
}

TEST_CASE("yelan sim: a grid writes one recording per member and a manifest", "[cli][sim]") {
  TempDir d;
  const Result g = cli({"sim", "--grid", "test", "--characters", "lena", "--motions", "dance", "--views", "front,back",
                        "--lights", "low", "--backgrounds", "static", "--duration", "40ms", "--out-dir", d / "grid"});
  INFO(g.err);
  REQUIRE(g.code == 0);
  CHECK(std::filesystem::exists(d / "grid/lena-dance-front-low-static.yelan.h5"));
  CHECK(std::filesystem::exists(d / "grid/lena-dance-back-low-static.yelan.h5"));
  const std::string m = slurp(d / "grid/manifest.json");
  CHECK(has(m, "\"preset\": \"lena-dance-back-low-static\""));
  CHECK(has(m, "\"split\": \"test\""));
  CHECK(std::filesystem::exists(d / "grid/lena-dance-back-low-static-occluded.yelan.h5"));  // the test split has both
  CHECK(has(g.err, "[4/4]"));
}

TEST_CASE("yelan sim --splits writes the split files, and --sim @FILE reads them with line numbers on errors", "[cli][sim]") {
  TempDir d;
  const Result r = cli({"sim", "--splits", d / "splits", "--seed", "3", "--scenes", "5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  auto lines = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);)
      if (!l.empty() && l[0] != '#') out.push_back(l);
    return out;
  };
  CHECK(lines(slurp(d / "splits/train.txt")).size() == 3696);
  const auto test = lines(slurp(d / "splits/test.txt"));
  CHECK(test.size() == 864);
  const auto drawn = lines(slurp(d / "splits/test-seed3-5.txt"));
  REQUIRE(drawn.size() == 5);
  for (const auto& n : drawn) CHECK(std::find(test.begin(), test.end(), n) != test.end());
  CHECK(has(slurp(d / "splits/test.txt"), "# regenerate: yelan sim --splits"));
  std::ofstream(d / "bad.txt") << "# a comment\n\nlena-dance-front-low-static\nlena-dance-sideways-low-static\n";
  const Result bad = cli({"train", "--stage", "pose", "--config", "tiny", "--sim", "@" + (d / "bad.txt"), "-o", d / "run"});
  CHECK(bad.code == 2);
  CHECK(has(bad.err, "bad.txt:4:"));
  CHECK(cli({"train", "--stage", "pose", "--config", "tiny", "--sim", "@" + (d / "missing.txt"), "-o", d / "run"}).code == 2);
}

TEST_CASE("yelan sim: bad arguments exit 2 and name the problem", "[cli][sim]") {
  TempDir d;
  CHECK(cli({"sim", "--preset", "front-high-static", "-o", d / "x.yelan.h5", "--duration", "soon"}).code == 2);
  const Result bad = cli({"sim", "--preset", "front-dim-static", "-o", d / "x.yelan.h5"});
  CHECK(bad.code == 2);
  CHECK(has(bad.err, "unknown lighting 'dim'"));
  CHECK(cli({"sim", "-o", d / "x.yelan.h5"}).code == 2);
  CHECK(cli({"sim", "--preset", "front-high-static", "-o", d / "x.txt"}).code == 2);
  CHECK(cli({"sim", "--grid", "everything", "--out-dir", d / "g"}).code == 2);
  std::ofstream(d / "s.json") << "{\"colour\": 3}";
  const Result j = cli({"sim", "--config", d / "s.json", "-o", d / "x.yelan.h5"});
  CHECK(j.code == 2);
  CHECK(has(j.err, "unknown key 'colour'"));
  CHECK_FALSE(std::filesystem::exists(d / "x.yelan.h5"));
  // A dataset's condition filter names its unknown word, and nothing is simulated.
  const Result o = cli({"sim", "--dataset", d / "ds", "--train", "1", "--val", "0", "--test", "0", "--only", "low-dim"});
  CHECK(o.code == 2);
  CHECK(has(o.err, "unknown scene word 'dim'"));
  const Result help = cli({"sim", "--help"});
  std::string text = help.out + help.err;
  std::replace(text.begin(), text.end(), '\n', ' ');
  for (const std::string& w : yelan::camera::sim::scene_vocabulary()) {
    INFO(w);
    CHECK((has(text, " " + w + " ") || has(text, " " + w + ")")));
  }
  const std::filesystem::path made = std::filesystem::path(d / "ds") / "train";
  CHECK((!std::filesystem::exists(made) || std::filesystem::is_empty(made)));
  const Result l = cli({"sim", "--list"});
  CHECK(l.code == 0);
  CHECK(has(l.out, "kurt"));
}
