#include <catch2/catch.hpp>

#include <cmath>

#include "weights_test_util.h"
#include "weights_tools/parse_json.h"
#include "weights_tools/manifest.h"

using namespace yelan;
using yelan::test::has;
using yelan::test::TempDir;
using yelan::test::yelan_cli;

TEST_CASE("yelan weights inspect: counts per group and every name and shape", "[weights][cli]") {
  TempDir dir("inspect");
  weights::save_weights(dir / "w.h5", test::sample_weights());
  const auto r = yelan_cli({"weights", "inspect", dir / "w.h5"});
  CHECK(r.code == 0);
  CHECK(r.err.empty());
  CHECK(has(r.out, "format:  yelan-weights, version 1\n"));
  CHECK(has(r.out, "config:  {\"name\":\"sample\",\"pose\":{\"stages\":1}}\n"));
  CHECK(has(r.out, "mask:    1 tensors, 7 parameters, 7 values with BN buffers\n"));
  CHECK(has(r.out, "pose:    3 tensors, 30 parameters, 34 values with BN buffers\n"));
  CHECK(has(r.out, "\npose/in_cnn.0.weight [3, 2, 1, 5]\npose/in_cnn.1.num_batches_tracked []\n"));

  const auto j = yelan_cli({"weights", "inspect", "--json", dir / "w.h5"});
  REQUIRE(j.code == 0);
  const nlohmann::ordered_json doc = weights::parse_json(j.out);
  CHECK(doc.at("version") == 1);
  CHECK(doc.at("config").at("name") == "sample");
  const nlohmann::ordered_json& pose = doc.at("groups").at("pose");
  CHECK(pose.at("tensors") == 3);
  CHECK(pose.at("parameters") == 30);
  CHECK(pose.at("values") == 34);
  CHECK(pose.at("shapes").at("in_cnn.0.weight").dump() == "[3,2,1,5]");
  CHECK(pose.at("shapes").at("in_cnn.1.num_batches_tracked").dump() == "[]");
}

TEST_CASE("yelan weights diff: max |a-b| per tensor, missing and reshaped tensors, exit 1", "[weights][cli]") {
  TempDir dir("diff");
  const weights::Weights a = test::sample_weights();
  weights::save_weights(dir / "a.h5", a);
  weights::save_weights(dir / "same.h5", a);
  auto same = yelan_cli({"weights", "diff", dir / "a.h5", dir / "same.h5"});
  CHECK(same.code == 0);
  CHECK(same.out == "summary: 4 tensors compared, 0 differ by more than 0, max |a-b| 0 "
                    "(mask/fc.bias); 0 only in A, 0 only in B, 0 shapes differ\n");

  weights::Weights b = a;
  b.groups["pose"]["in_cnn.0.weight"].data[17] += 0.5f;
  weights::save_weights(dir / "b.h5", b);
  auto d = yelan_cli({"weights", "diff", dir / "a.h5", dir / "b.h5"});
  CHECK(d.code == 1);
  CHECK(d.out == "pose/in_cnn.0.weight max |a-b| 0.5\n"
                 "summary: 4 tensors compared, 1 differ by more than 0, max |a-b| 0.5 "
                 "(pose/in_cnn.0.weight); 0 only in A, 0 only in B, 0 shapes differ\n");
  CHECK(yelan_cli({"weights", "diff", "--tol", "0.5", dir / "a.h5", dir / "b.h5"}).code == 0);
  CHECK(yelan_cli({"weights", "diff", "--tol=0.4", dir / "a.h5", dir / "b.h5"}).code == 1);
  auto all = yelan_cli({"weights", "diff", "--all", "--tol", "1", dir / "a.h5", dir / "b.h5"});
  CHECK(all.code == 0);
  CHECK(has(all.out, "mask/fc.bias max |a-b| 0\n"));
  CHECK(has(all.out, "pose/in_cnn.1.running_var max |a-b| 0\n"));

  weights::Weights c = a;
  c.groups["pose"].erase("in_cnn.1.running_var");
  c.groups["pose"]["new"] = {{1}, {0}};
  c.groups["mask"]["fc.bias"] = {{6}, {1, -1, 2, -2, 3, -3}};
  c.config_json = R"({"name":"other"})";
  weights::save_weights(dir / "c.h5", c);
  auto e = yelan_cli({"weights", "diff", dir / "a.h5", dir / "c.h5"});
  CHECK(e.code == 1);
  CHECK(e.out == "shape differs: mask/fc.bias [7] vs [6]\n"
                 "only in A: pose/in_cnn.1.running_var\n"
                 "only in B: pose/new\n"
                 "config differs\n"
                 "summary: 2 tensors compared, 0 differ by more than 0, max |a-b| 0 (pose/in_cnn.0.weight); "
                 "1 only in A, 1 only in B, 1 shapes differ\n");
}

TEST_CASE("yelan weights diff: NaN equals NaN, NaN against a number is an infinite difference", "[weights][cli]") {
  TempDir dir("nan");
  weights::Weights a = test::sample_weights();
  a.groups["mask"]["fc.bias"].data[3] = NAN;
  weights::save_weights(dir / "a.h5", a);
  weights::save_weights(dir / "a2.h5", a);
  CHECK(yelan_cli({"weights", "diff", dir / "a.h5", dir / "a2.h5"}).code == 0);
  weights::Weights b = a;
  b.groups["mask"]["fc.bias"].data[3] = 0;
  weights::save_weights(dir / "b.h5", b);
  auto r = yelan_cli({"weights", "diff", "--tol", "1e30", dir / "a.h5", dir / "b.h5"});
  CHECK(r.code == 1);
  CHECK(has(r.out, "mask/fc.bias max |a-b| inf\n"));
}

TEST_CASE("yelan weights verify: ok, mismatches exit 2 one line each, config drift warns", "[weights][cli]") {
  TempDir dir("cliverify");
  const weights::Manifest m = weights::find_manifest("tiny");
  weights::Weights w;
  w.config_json = m.config_json;
  for (const auto& [g, tensors] : m.groups)
    for (const auto& [name, shape] : tensors)
      w.groups[g][name] = {shape, std::vector<float>(static_cast<std::size_t>(weights::element_count(shape)))};
  weights::save_weights(dir / "ok.h5", w);
  auto ok = yelan_cli({"weights", "verify", dir / "ok.h5", "--config", "tiny"});
  CHECK(ok.code == 0);
  CHECK(ok.err.empty());
  CHECK(ok.out == "ok: " + (dir / "ok.h5") + " holds every tensor of config 'tiny' with its shape; "
                  "mask 124 tensors, 489456 parameters; pose 1216 tensors, 246550 parameters\n");

  w.config_json = R"({"name":"tiny","input":{"window":5}})";
  weights::save_weights(dir / "drift.h5", w);
  auto drift = yelan_cli({"weights", "verify", dir / "drift.h5", "--config", "tiny"});
  CHECK(drift.code == 0);
  CHECK(has(drift.err, "yelan: warning: " + (dir / "drift.h5") + ": its config differs from " + m.path +
                           " in input.channels, input.downscale, input.sensor_height, input.sensor_width, "
                           "input.window, mask, pose (the tensors match)\n"));

  w.groups["pose"].erase("cl.fuse_list.0.weight");
  weights::save_weights(dir / "bad.h5", w);
  auto bad = yelan_cli({"weights", "verify", dir / "bad.h5", "--config", "tiny"});
  CHECK(bad.code == 2);
  CHECK(bad.out.empty());
  CHECK(bad.err == "yelan: error: " + (dir / "bad.h5") + ": does not match config 'tiny' (" + m.path + ")\n" +
                       "yelan: error: " + (dir / "bad.h5") + " (pose): 1 missing: cl.fuse_list.0.weight\n");
}

TEST_CASE("yelan weights: usage errors exit 2, missing files exit 2", "[weights][cli]") {
  struct Case { std::vector<std::string> argv; int code; std::string says; };
  for (const Case& c : std::vector<Case>{
           {{"weights"}, 2, "weights needs a subcommand: inspect, diff or verify"},
           {{"weights", "frob"}, 2, "unknown weights subcommand 'frob'"},
           {{"weights", "inspect"}, 2, "expected 1 argument(s), got 0"},
           {{"weights", "inspect", "a.h5", "--bogus"}, 2, "unknown option '--bogus'"},
           {{"weights", "diff", "a.h5"}, 2, "expected 2 argument(s), got 1"},
           {{"weights", "diff", "--tol", "-1", "a", "b"}, 2, "--tol expects a finite number >= 0, got '-1'"},
           {{"weights", "diff", "--tol", "nan", "a", "b"}, 2, "--tol expects a finite number >= 0, got 'nan'"},
           {{"weights", "verify", "a.h5"}, 2, "weights verify needs --config NAME|FILE"},
           {{"weights", "verify", "a.h5", "--config", "no-such-config"}, 2, "no config named 'no-such-config'"},
           {{"weights", "inspect", "/nonexistent/w.h5"}, 2, "yelan: error: /nonexistent/w.h5: no such file\n"},
           {{"weights", "init", "--config", "tiny"}, 2, "weights init needs --config NAME|FILE --seed N -o W.h5"},
       }) {
    INFO(c.says);
    const auto r = yelan_cli(c.argv);
    CHECK(r.code == c.code);
    CHECK(has(r.err, c.says));
    CHECK(r.out.empty());
  }
  const auto help = yelan_cli({"weights", "--help"});
  CHECK(help.code == 0);
  CHECK(has(help.out, "yelan weights verify FILE --config NAME|FILE"));
}
