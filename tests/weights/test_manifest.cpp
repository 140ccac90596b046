#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>

#include "weights_test_util.h"
#include "weights_tools/manifest.h"

using namespace yelan;
using yelan::test::TempDir;
using weights::WeightsError;

namespace {

// A weights file holding exactly the tensors of a manifest (zeros), for `edit` to spoil.
void write_from_manifest(const std::string& path, const weights::Manifest& m,
                         const std::function<void(weights::Weights&)>& edit = {}) {
  weights::Weights w;
  w.config_json = m.config_json;
  for (const auto& [g, tensors] : m.groups)
    for (const auto& [name, shape] : tensors)
      w.groups[g][name] = {shape, std::vector<float>(static_cast<std::size_t>(weights::element_count(shape)))};
  if (edit) edit(w);
  weights::save_weights(path, w);
}

std::int64_t parameters(const weights::Manifest& m, const std::string& g) {
  std::int64_t n = 0;
  for (const auto& [name, shape] : m.groups.at(g))
    if (weights::is_parameter(name)) n += weights::element_count(shape);
  return n;
}

std::string verify_error(const std::string& path, const weights::Manifest& m) {
  try {
    weights::verify(weights::WeightsReader(path), m);
  } catch (const WeightsError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string find_error(const std::string& what) {
  try {
    weights::find_manifest(what);
  } catch (const WeightsError& e) {
    return e.what();
  }
  return "(no error)";
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST_CASE("manifest: the paper config has the paper's parameter counts", "[weights][manifest]") {
  const weights::Manifest m = weights::find_manifest("paper");
  CHECK(m.config_name == "paper");
  CHECK(m.groups.at("pose").size() == 1774);
  CHECK(m.groups.at("mask").size() == 124);
  CHECK(parameters(m, "pose") == 20390199);
  CHECK(parameters(m, "mask") == 31196768);
  CHECK(m.groups.at("pose").at("cl.cell_list.0.conv.weight") == weights::Shape{512, 256, 3, 3});
  CHECK(m.groups.at("pose").at("in_cnn.1.num_batches_tracked").empty());
  CHECK(m.groups.at("mask").at("up1.up.weight") == weights::Shape{1024, 512, 2, 2});
  // small: quarter width, causal (fuse takes h, not 2h).
  const weights::Manifest small = weights::find_manifest("small");
  CHECK(small.groups.at("pose").at("cl.fuse_list.0.weight") == weights::Shape{32, 32, 1, 1});
  CHECK(parameters(small, "pose") == 946202);
}

TEST_CASE("manifest: verify accepts the exact tensor set and names every difference", "[weights][manifest]") {
  TempDir dir("verify");
  const weights::Manifest m = weights::find_manifest("tiny");
  write_from_manifest(dir / "ok.h5", m);
  CHECK(verify_error(dir / "ok.h5", m) == "(no error)");
  CHECK(weights::compare_with_manifest(weights::WeightsReader(dir / "ok.h5"), m).empty());

  write_from_manifest(dir / "bad.h5", m, [](weights::Weights& w) {
    w.groups["pose"].erase("cl.fuse_list.0.bias");
    w.groups["pose"]["cl.extra"] = {{2}, {0, 0}};
    w.groups["pose"]["in_cnn.0.weight"] = {{8, 6, 7, 5}, std::vector<float>(8 * 6 * 7 * 5)};
    w.groups["mask"]["fc.bias"] = {{}, {0}};
  });
  const std::string f = dir / "bad.h5";
  CHECK(verify_error(f, m) == f + ": does not match config 'tiny' (" + m.path + ")\n" +
                                  f + " (mask): fc.bias: shape [], expected [4]\n" +
                                  f + " (pose): 1 missing: cl.fuse_list.0.bias\n" +
                                  f + " (pose): 1 unexpected: cl.extra\n" +
                                  f + " (pose): in_cnn.0.weight: shape [8, 6, 7, 5], expected [8, 6, 7, 7]");
}

TEST_CASE("manifest: a file of another config is summarised, not listed in full", "[weights][manifest]") {
  TempDir dir("other");
  write_from_manifest(dir / "tiny.h5", weights::find_manifest("tiny"));
  const auto lines =
      weights::compare_with_manifest(weights::WeightsReader(dir / "tiny.h5"), weights::find_manifest("paper"));
  // paper has 3 stages, tiny 2: 1 missing/unexpected line per group at most, 10 shapes, 1 summary.
  REQUIRE(lines.size() <= 2 * 12);
  CHECK(test::has(lines.back(), "more tensors with a wrong shape"));
  bool listed_missing = false;
  for (const auto& l : lines)
    if (test::has(l, "(pose): 558 missing: hm_combiners.1.combine_block.module.0.weight, ")) {
      listed_missing = true;
      CHECK(test::has(l, ", ... (538 more)"));
    }
  CHECK(listed_missing);
}

TEST_CASE("manifest: found by name, by config file, by manifest file or in $YELAN_CONFIG_DIR", "[weights][manifest]") {
  TempDir dir("find");
  const weights::Manifest tiny = weights::find_manifest("tiny");
  const std::string config_file = (std::filesystem::path(tiny.path).parent_path() / "tiny.json").string();
  CHECK(weights::find_manifest(config_file).path == tiny.path);
  CHECK(weights::find_manifest(tiny.path).groups == tiny.groups);

  std::filesystem::copy_file(tiny.path, dir / "mine.manifest.json");
  write_text(dir / "lonely.json", R"({"name":"lonely"})");
  ::setenv("YELAN_CONFIG_DIR", dir.path.c_str(), 1);
  const weights::Manifest mine = weights::find_manifest("mine");
  const std::string nope = find_error("nope");
  ::unsetenv("YELAN_CONFIG_DIR");
  CHECK(mine.groups == tiny.groups);
  CHECK(nope == "no config named 'nope' (" + (dir / "nope.manifest.json") +
                    " does not exist; weights_tools/make_manifest.py writes it)");
  CHECK(find_error(dir / "lonely.json") ==
        dir / "lonely.json" + ": a config without a manifest (expected " + (dir / "lonely.manifest.json") +
            "; run weights_tools/make_manifest.py " + (dir / "lonely.json") + ")");
  CHECK(find_error(dir / "absent.json") == dir / "absent.json" + ": no such file");
}

TEST_CASE("manifest: malformed manifests are refused with the reason", "[weights][manifest]") {
  TempDir dir("badmanifest");
  const std::string head = R"({"format":"yelan-weights-manifest","version":1,"config":{"name":"x"},"groups":)";
  struct Case { std::string text, problem; };
  for (const Case& c : std::vector<Case>{
           {"{\"format\": ", "not valid JSON: offset 11: unexpected end of text"},
           {R"({"format":"yelan-weights","version":1})", "not a weights manifest (format is not 'yelan-weights-manifest')"},
           {R"({"format":"yelan-weights-manifest","version":2})", "manifest version is not 1"},
           {head + R"({"mask":[]}})", "manifest has no list for group 'pose'"},
           {head + R"({"mask":[],"pose":[{"name":"a","shape":[2,-1]}]}})",
            "groups.pose[0] (a): shape holds a non-integer or absurd size"},
           {head + R"({"mask":[],"pose":[{"name":"a","shape":[2.5]}]}})",
            "groups.pose[0] (a): shape holds a non-integer or absurd size"},
           {head + R"({"mask":[],"pose":[{"name":"a","shape":[2]},{"name":"a","shape":[2]}]}})",
            "groups.pose[1]: 'a' listed twice"},
           {head + R"({"mask":[{"shape":[1]}],"pose":[]}})", "groups.mask[0] needs a string 'name' and an array 'shape'"},
       }) {
    INFO(c.text);
    write_text(dir / "m.manifest.json", c.text);
    CHECK(find_error(dir / "m.manifest.json") == dir / "m.manifest.json" + ": " + c.problem);
  }
}
