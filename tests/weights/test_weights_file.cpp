#include <catch2/catch.hpp>

#include <sys/resource.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "camera/io/untrusted.h"
#include "weights_test_util.h"

using namespace yelan;
using yelan::test::RawH5;
using yelan::test::TempDir;
using weights::WeightsError;

namespace {

std::string error_of(const std::string& path) {
  try {
    weights::WeightsReader r(path);
  } catch (const WeightsError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST_CASE("weights file: save then load gives back every value, shape and the config", "[weights]") {
  TempDir dir("roundtrip");
  const weights::Weights w = test::sample_weights();
  weights::save_weights(dir / "w.h5", w);
  CHECK(dir.listing() == std::vector<std::string>{"w.h5"});  // the temp file was renamed
  const weights::Weights back = weights::load_weights(dir / "w.h5");
  CHECK(back.config_json == w.config_json);
  REQUIRE(back.groups.size() == 2);
  for (const auto& [g, tensors] : w.groups) {
    REQUIRE(back.groups.at(g).size() == tensors.size());
    for (const auto& [name, t] : tensors) {
      INFO(g << "/" << name);
      CHECK(back.groups.at(g).at(name).shape == t.shape);
      CHECK(back.groups.at(g).at(name).data == t.data);  // bit-exact floats
    }
  }
  weights::WeightsReader r(dir / "w.h5");
  CHECK(r.version() == 1);
  REQUIRE(r.tensors("pose").size() == 3);
  CHECK(r.tensors("pose")[1].name == "in_cnn.1.num_batches_tracked");
  CHECK(r.tensors("pose")[1].shape.empty());
  CHECK(r.find("mask", "fc.bias") != nullptr);
  CHECK(r.find("mask", "fc.weight") == nullptr);
}

TEST_CASE("weights file: no time stamps, so equal weights give equal bytes", "[weights]") {
  TempDir dir("bytes");
  weights::save_weights(dir / "a.h5", test::sample_weights());
  weights::save_weights(dir / "b.h5", test::sample_weights());
  const std::string a = bytes_of(dir / "a.h5"), b = bytes_of(dir / "b.h5");
  CHECK(a.size() > 1000);
  CHECK(a == b);
  // Equal bytes within one second prove little: check that no object carries a time.
  hid_t f = H5Fopen((dir / "a.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  for (const char* obj : {"/", "/mask", "/pose", "/pose/in_cnn.0.weight", "/mask/fc.bias"}) {
    INFO(obj);
    H5O_info_t info{};
    REQUIRE(H5Oget_info_by_name(f, obj, &info, H5P_DEFAULT) >= 0);
    CHECK(info.ctime == 0);
    CHECK(info.mtime == 0);
  }
  H5Fclose(f);
}

TEST_CASE("weights file: a failed save leaves the old file and no temp file", "[weights]") {
  TempDir dir("atomic");
  weights::save_weights(dir / "w.h5", test::sample_weights());
  const std::string before = bytes_of(dir / "w.h5");
  weights::Weights bad = test::sample_weights();
  bad.groups["pose"]["in_cnn.1.running_var"].data.pop_back();  // 2 values for shape [3]
  CHECK_THROWS_WITH(weights::save_weights(dir / "w.h5", bad),
                    "weights tensor 'pose/in_cnn.1.running_var': bad name or 2 values for shape [3]");
  weights::Weights other_group = test::sample_weights();
  other_group.groups["extra"];
  CHECK_THROWS_AS(weights::save_weights(dir / "w.h5", other_group), std::invalid_argument);
  CHECK_THROWS_AS(weights::save_weights(dir / "no_such_dir/w.h5", test::sample_weights()), WeightsError);
  CHECK(bytes_of(dir / "w.h5") == before);
  CHECK(dir.listing() == std::vector<std::string>{"w.h5"});
}

TEST_CASE("weights file: reads what h5py writes (variable-length UTF-8 attributes)", "[weights]") {
  const weights::Weights w = weights::load_weights(test::fixture("h5py_written.h5"));
  CHECK(w.config_json == "{\"name\":\"fixture\",\"note\":\"caf\\u00e9 \\\"quoted\\\"\"}");
  CHECK(w.groups.at("mask").at("fc.bias").data == std::vector<float>{0.5f, -1.25f, 3.0f, 1e-7f});
  const auto& conv = w.groups.at("pose").at("in_cnn.0.weight");
  CHECK(conv.shape == weights::Shape{2, 1, 3, 3});
  for (std::size_t i = 0; i < conv.data.size(); ++i) CHECK(conv.data[i] == static_cast<float>(i) / 8.f);
  const auto& count = w.groups.at("pose").at("in_cnn.1.num_batches_tracked");
  CHECK(count.shape.empty());
  CHECK(count.data == std::vector<float>{16777216.f});
}

// Found by CI's fuzz run: on this file Debian 12's libhdf5 (1.10.8) loops inside its own
// reader, so only the vetting child's CPU limit ends the read. The shipped limit is 120 s;
// a 2 s limit shows the same refusal in a test's time.
TEST_CASE("weights file: one on which libhdf5 spins is refused at the vetting child's CPU limit", "[weights]") {
  const std::string hang = (std::filesystem::path(__FILE__).parent_path().parent_path() / "fuzz" / "hangs" /
                            "weights-libhdf5-spins-120s.h5").string();
  REQUIRE(std::filesystem::exists(hang));
  camera::UntrustedLimits quick;
  quick.seconds = 2;
  CHECK_THROWS_WITH(camera::vet_in_child(hang, [&] { weights::load_weights(hang); }, quick),
                    Catch::Contains("more than 2 s of CPU"));
}

// Found by CI's fuzz run (2026-12-05): the root attribute 'format' of this 10 kB file is a
// variable-length string whose stored length says 1.9 GB, and libhdf5 allocates that before it
// finds the heap object missing. The vetting child takes it and fails; the process itself must
// not read it again to say why (it did: 1.9 GB resident to reject 10 kB).
TEST_CASE("weights file: a string that asks libhdf5 for 2 GB is refused without a second read", "[weights]") {
  const std::string greedy = (std::filesystem::path(__FILE__).parent_path().parent_path() / "fuzz" / "greedy" /
                              "weights-vlen-string-asks-2gb.h5").string();
  REQUIRE(std::filesystem::exists(greedy));
  camera::forget_vetted_files();
  struct rusage before {};
  ::getrusage(RUSAGE_SELF, &before);
  CHECK_THAT(error_of(greedy), Catch::Contains("not read again") && Catch::Contains(greedy));
  struct rusage after {};
  ::getrusage(RUSAGE_SELF, &after);
  CHECK(after.ru_maxrss - before.ru_maxrss < 256L << 10);  // KiB: this process never held the 1.9 GB
}

TEST_CASE("weights file: foreign and damaged files give one exact message each", "[weights]") {
  TempDir dir("bad");
  const auto p = [&](const std::string& f) { return dir / f; };
  std::ofstream(p("text.h5")) << "this is not HDF5\n";
  std::filesystem::create_directories(p("folder.h5"));
  { RawH5 f(p("no_format.h5")); }
  { RawH5 f(p("recording.h5")); f.header("yelan-recording"); }
  { RawH5 f(p("v2.h5")); f.header("yelan-weights", 2); }
  { RawH5 f(p("version_str.h5")); f.str_attr("format", "yelan-weights"); f.str_attr("version", "1"); }
  { RawH5 f(p("no_config.h5")); f.str_attr("format", "yelan-weights"); f.int_attr("version", 1); }
  { RawH5 f(p("config_bad.h5")); f.header("yelan-weights", 1, "{"); }
  { RawH5 f(p("config_array.h5")); f.header("yelan-weights", 1, "[1]"); }
  { RawH5 f(p("no_mask.h5")); f.header(); f.group("pose"); }
  { RawH5 f(p("extra_root.h5")); f.header(); f.group("mask"); f.group("pose"); f.group("extra"); }
  { RawH5 f(p("pose_dataset.h5")); f.header(); f.group("mask"); f.dataset(f.root(), "pose", H5T_IEEE_F32LE, {2}); }
  { RawH5 f(p("f64.h5")); f.header(); f.group("mask"); f.dataset(f.group("pose"), "w", H5T_IEEE_F64LE, {2, 3}); }
  { RawH5 f(p("i32.h5")); f.header(); f.group("mask"); f.dataset(f.group("pose"), "w", H5T_STD_I32LE, {2}); }
  { RawH5 f(p("subgroup.h5")); f.header(); f.group("mask"); f.group("pose"); f.group("pose/sub"); }
  {
    RawH5 f(p("softlink.h5"));
    f.header();
    f.group("mask");
    hid_t pose = f.group("pose");
    f.dataset(pose, "real", H5T_IEEE_F32LE, {2});
    H5Lcreate_soft("/pose/real", pose, "link", H5P_DEFAULT, H5P_DEFAULT);
  }
  { RawH5 f(p("huge.h5")); f.header(); f.group("mask"); f.dataset(f.group("pose"), "huge", H5T_IEEE_F32LE, {1u << 20, 1u << 20}, false, true); }
  { RawH5 f(p("unwritten.h5")); f.header(); f.group("mask"); f.dataset(f.group("pose"), "w", H5T_IEEE_F32LE, {4}, false); }

  struct Case { std::string file, problem; };
  for (const Case& c : std::vector<Case>{
           {"absent.h5", "no such file"},
           {"folder.h5", "not a regular file"},
           {"text.h5", "not an HDF5 file"},
           {"no_format.h5", "root attribute 'format' is missing (not a yelan weights file)"},
           {"recording.h5", "format is 'yelan-recording', expected 'yelan-weights'"},
           {"v2.h5", "version 2 is not supported (this build reads version 1)"},
           {"version_str.h5", "root attribute 'version' is not an integer"},
           {"no_config.h5", "root attribute 'config' is missing"},
           {"config_bad.h5", "root attribute 'config' is not valid JSON: offset 1: expected a string key"},
           {"config_array.h5", "root attribute 'config' is not a JSON object"},
           {"no_mask.h5", "group '/mask' is missing"},
           {"extra_root.h5", "unexpected object '/extra' at the root"},
           {"pose_dataset.h5", "'/pose' is not a group"},
           {"f64.h5", "/pose/w is float64, expected float32"},
           {"i32.h5", "/pose/w is int32, expected float32"},
           {"subgroup.h5", "/pose/sub is not a dataset"},
           {"softlink.h5", "/pose/link is not a dataset"},
           {"huge.h5", "/pose/huge claims shape [1048576, 1048576], more than 2^30 elements"},
           {"unwritten.h5", "/pose/w has no data stored"},
       }) {
    INFO(c.file);
    CHECK(error_of(p(c.file)) == p(c.file) + ": " + c.problem);
  }
}

TEST_CASE("weights file: a truncated file is refused, never read past its end", "[weights]") {
  TempDir dir("truncated");
  weights::Weights w = test::sample_weights();
  w.groups["pose"]["big"] = {{64, 64}, std::vector<float>(64 * 64, 1.5f)};
  weights::save_weights(dir / "w.h5", w);
  const std::string full = bytes_of(dir / "w.h5");
  for (double keep : {0.95, 0.7, 0.5, 0.2, 0.01}) {
    INFO("kept " << keep);
    const std::string cut = dir / ("cut" + std::to_string(static_cast<int>(keep * 100)) + ".h5");
    std::ofstream(cut, std::ios::binary) << full.substr(0, static_cast<std::size_t>(keep * full.size()));
    const std::string e = error_of(cut);
    CHECK(e.rfind(cut + ": ", 0) == 0);
    CHECK((test::has(e, "truncated") || test::has(e, "not an HDF5 file")));
  }
}

TEST_CASE("weights file: overwritten bytes give an error or a readable file, never a crash", "[weights]") {
  TempDir dir("garbage");
  weights::save_weights(dir / "w.h5", test::sample_weights());
  const std::string full = bytes_of(dir / "w.h5");
  int refused = 0;
  for (std::size_t at = 0; at + 16 <= full.size(); at += full.size() / 23) {
    std::string damaged = full;
    for (std::size_t i = 0; i < 16; ++i) damaged[at + i] = static_cast<char>(0xA5 ^ (i * 37));
    std::ofstream(dir / "d.h5", std::ios::binary | std::ios::trunc) << damaged;
    try {
      weights::load_weights(dir / "d.h5");
    } catch (const WeightsError& e) {
      CHECK(std::string(e.what()).rfind(dir / "d.h5", 0) == 0);
      ++refused;
    }
  }
  CHECK(refused > 0);  // the superblock at least is checked
}

TEST_CASE("weights file: every tensor carries a checksum; a flipped byte is found on load, naming the tensor", "[weights]") {
  TempDir dir("checksum");
  weights::save_weights(dir / "w.h5", test::sample_weights());
  REQUIRE_NOTHROW(weights::load_weights(dir / "w.h5"));
  // Where the bytes of /mask/fc.bias lie in the file (contiguous storage).
  haddr_t offset = HADDR_UNDEF;
  {
    const hid_t f = H5Fopen((dir / "w.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    REQUIRE(f >= 0);
    const hid_t ds = H5Dopen2(f, "/mask/fc.bias", H5P_DEFAULT);
    REQUIRE(ds >= 0);
    offset = H5Dget_offset(ds);
    H5Dclose(ds);
    H5Fclose(f);
  }
  REQUIRE(offset != HADDR_UNDEF);
  std::string bytes = bytes_of(dir / "w.h5");
  bytes[std::size_t(offset) + 1] = char(bytes[std::size_t(offset) + 1] ^ 0x10);
  std::ofstream(dir / "w.h5", std::ios::binary | std::ios::trunc) << bytes;
  CHECK_THROWS_WITH(weights::load_weights(dir / "w.h5"), Catch::Contains("tensor /mask/fc.bias: checksum mismatch"));
}
