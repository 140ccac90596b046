// The files a command is handed, as a hostile or a foreign world makes them (issue 17): links
// planted at an output or at its temporary names (row 4), recordings another tool wrote
// (rows 21, 22), an output that is one of the inputs (Deliver 4).
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "camera/io/format_error.h"
#include "camera/io/h5.h"
#include "camera/sim/recording_reader.h"
#include "cli_util.h"

namespace fs = std::filesystem;
namespace h5 = yelan::camera::h5;
using yelan::test::CliTempDir;
using yelan::test::contains;
using yelan::test::run_cli;
using yelan::test::slurp;

namespace {

const std::string kModel = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
// Written by h5py the ordinary way (tests/data/make_h5py_recording.py): variable-length UTF-8
// string attributes, the sensor size only in /camera/width and /camera/height.
const std::string kH5py = std::string(YELAN_SOURCE_DIR) + "/tests/data/h5py_recording.yelan.h5";

// The real binary, started only once `plant` (given its pid) has run: names made from the
// pid can be taken before the command could take them. Its exit code, as run_binary's.
int run_planted(const std::vector<std::string>& args, const std::function<void(pid_t)>& plant) {
  int gate[2];
  REQUIRE(::pipe2(gate, O_CLOEXEC) == 0);
  const pid_t child = yelan::test::spawn(YELAN_BINARY, args, "/dev/null", gate[0]);
  ::close(gate[0]);
  REQUIRE(child > 0);
  plant(child);
  const bool released = ::write(gate[1], "x", 1) == 1;
  ::close(gate[1]);  // without the byte the child exits 125
  CHECK(released);
  return yelan::test::wait_child(child, 300);
}

int csv_rows(const std::string& path) {
  std::ifstream f(path);
  int rows = -1;  // the header
  for (std::string l; std::getline(f, l);) ++rows;
  return rows;
}

bool variable_length_string(const std::string& path, const char* attr) {
  const h5::H5Id f = h5::open_file(path);
  const h5::H5Id a = h5::check(H5Aopen(f.get(), attr, H5P_DEFAULT), attr);
  const h5::H5Id t = h5::check(H5Aget_type(a.get()), attr);
  return H5Tis_variable_str(t.get()) > 0;
}

}  // namespace

TEST_CASE("convert and run --out write nothing through a link planted at OUT or at its temporary names", "[cli]") {
  CliTempDir d("planted");
  const std::string victim = d / "victim";
  std::ofstream(victim) << "precious";
  const std::vector<std::pair<std::vector<std::string>, std::string>> commands = {
      {{"convert", kH5py, d / "out.txt"}, d / "out.txt"},
      {{"run", "--weights", kModel, kH5py, "--out", d / "out.csv"}, d / "out.csv"},
  };
  for (const auto& [cmd, out] : commands) {
    INFO(cmd[0]);
    // OUT a link: the finished file is renamed over the link itself, the victim untouched.
    fs::create_symlink(victim, out);
    CHECK(yelan::test::run_binary(YELAN_BINARY, cmd, 300) == 0);
    CHECK_FALSE(fs::is_symlink(out));
    CHECK(fs::file_size(out) > 100);
    CHECK(slurp(victim) == "precious");
    fs::remove(out);
    // Links at the names that can be predicted, made from the pid: OUT.tmp-PID (the old
    // temporary name) and .OUT.probe-PID (the old writability probe, which refused the run
    // while a link held its name). Both are TempFiles now: NAME.tmp-PID-<8 random>.
    std::vector<std::string> links;
    const int code = run_planted(cmd, [&](pid_t pid) {
      const std::string p = std::to_string(pid), name = fs::path(out).filename().string();
      links = {out + ".tmp-" + p, d / ("." + name + ".probe-" + p)};
      for (const auto& l : links) fs::create_symlink(victim, l);
    });
    CHECK(code == 0);  // a planted name neither is written through nor stops the command
    CHECK(slurp(victim) == "precious");
    CHECK(fs::is_regular_file(fs::symlink_status(out)));
    if (cmd[0] == "run") CHECK(csv_rows(out) >= 1);
    for (const auto& l : links) CHECK(fs::read_symlink(l) == victim);
    for (const auto& l : links) fs::remove(l);
    fs::remove(out);
  }
}

TEST_CASE("recordings another tool wrote (h5py's strings, the sensor size in /camera only): info, run and eval", "[cli]") {
  CliTempDir d("foreign");
  // The fixture as h5py wrote it, and two copies that keep one of its traits each.
  for (const char* sub : {"h5py", "strings", "camera"}) {
    fs::create_directories(d.p / sub);
    fs::copy_file(kH5py, d.p / sub / "r.yelan.h5");
  }
  {  // strings: the root width/height our writer adds, so only the string form is foreign
    const h5::H5Id f = h5::check(H5Fopen((d / "strings/r.yelan.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open");
    h5::write_attr_i64(f.get(), "width", 346);
    h5::write_attr_i64(f.get(), "height", 260);
  }
  {  // camera: fixed-length strings as ours, so only the missing root size is foreign
    const h5::H5Id f = h5::check(H5Fopen((d / "camera/r.yelan.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open");
    for (const char* a : {"format", "character", "motion", "view", "lighting", "background"}) {
      const auto v = h5::read_attr_string(f.get(), a);
      REQUIRE(v);
      REQUIRE(H5Adelete(f.get(), a) >= 0);
      h5::write_attr_string(f.get(), a, *v);
    }
  }
  REQUIRE(variable_length_string(d / "h5py/r.yelan.h5", "format"));
  REQUIRE(variable_length_string(d / "strings/r.yelan.h5", "format"));
  REQUIRE_FALSE(variable_length_string(d / "camera/r.yelan.h5", "format"));
  for (const char* sub : {"h5py", "strings", "camera"}) {
    INFO(sub);
    const std::string rec = d / (std::string(sub) + "/r.yelan.h5");
    const auto info = run_cli({"info", rec, "--json"});
    INFO(info.err);
    CHECK(info.code == 0);
    CHECK(contains(info.out, "\"format\": \"yelan-h5\", \"width\": 346, \"height\": 260, \"events\": 212,"));
    const auto run = run_cli({"run", "--weights", kModel, rec, "--out", d / "p.csv"});
    INFO(run.err);
    CHECK(run.code == 0);
    CHECK(csv_rows(d / "p.csv") == 12);  // 0.26 s at 50 per second
    const auto eval = run_cli({"eval", "--weights", kModel, "--data", d / sub, "--no-floors"});
    INFO(eval.err);
    CHECK(eval.code == 0);
    CHECK(contains(eval.out, ", 1 scenes, 8 frames"));  // one window after the 0.1 s warm-up
    CHECK(contains(eval.out, "character:  lena"));      // the string attributes read
  }
}

TEST_CASE("an output that is one of the inputs is refused with exit 2, naming it, before any work", "[cli]") {
  CliTempDir d("same-file");
  const std::string in = d / "in.yelan.h5", w = d / "w.h5", cfg = d / "c.json", scene = d / "scene.yelan.h5";
  fs::copy_file(kH5py, in);
  fs::copy_file(kModel, w);
  fs::copy_file(std::string(YELAN_SOURCE_DIR) + "/weights_tools/configs/micro.json", cfg);
  std::ofstream(scene) << "{}";
  fs::create_directories(d.p / "recs");
  fs::copy_file(kH5py, d.p / "recs/r.yelan.h5");
  // The same file under other names: through "/./", a hard link and a symbolic link.
  const std::string dot = d.p.string() + "/./in.yelan.h5", hard = d / "hard.yelan.h5", soft = d / "soft.h5";
  fs::create_hard_link(in, hard);
  fs::create_symlink(w, soft);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"convert", in, dot}, "OUT " + dot},
      {{"convert", in, hard}, "OUT " + hard},
      {{"repr", "--type", "tore", "--fps", "50", in, hard}, "OUT " + hard},
      {{"model", "forward", "--weights", w, "--input", in, "--output", dot}, "--output " + dot},
      {{"model", "forward", "--weights", w, "--input", in, "--output", soft}, "--output " + soft},
      {{"weights", "combine", "--mask", w, "--pose", w, "-o", soft}, "-o " + soft},
      {{"weights", "init", "--config", cfg, "--seed", "1", "-o", cfg}, "-o " + cfg},
      {{"eval", "--weights", w, "--data", d / "recs", "--json", soft}, "--json " + soft},
      {{"sim", "--config", scene, "-o", scene}, "-o " + scene},
      {{"run", "--weights", w, in, "--out", hard}, "--out " + hard},
      {{"bench", "kernels", "--from", cfg, "--chart", cfg}, "--chart " + cfg},
      {{"bench", "early-exit", "--weights", w, "--chart", soft}, "--chart " + soft},
      {{"bench", "train", "--config", cfg, "--keep-data", cfg}, "--keep-data " + cfg},
  };
  const std::string in_bytes = slurp(in), w_bytes = slurp(w), cfg_bytes = slurp(cfg);
  for (const auto& [argv, names] : cases) {
    INFO(argv[0] << " " << argv[1] << " -> " << names);
    const auto r = run_cli(argv);
    INFO(r.err);
    CHECK(r.code == 2);
    CHECK(contains(r.err, names + " is an input"));
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);  // refused before any progress or report
    CHECK(r.out.empty());
  }
  CHECK((slurp(in) == in_bytes));  // the inputs untouched (bytes not printed on failure)
  CHECK((slurp(w) == w_bytes));
  CHECK((slurp(cfg) == cfg_bytes));
  CHECK((slurp(scene) == "{}"));
}

// A 24 KB file `scripts/fuzz recording` made: masks/t declares integers of 1.9 GB each, and
// HDF5 sizes its conversion buffer from that before reading one (2 GB, then 10-30 s).
TEST_CASE("a recording whose dataset declares 2 GB integers is refused before HDF5 allocates for them", "[cli]") {
  const std::string f = std::string(YELAN_SOURCE_DIR) + "/tests/data/fuzz-2gb-integer.yelan.h5";
  try {
    yelan::camera::sim::read_recording_info(f);
    FAIL("read_recording_info accepted " << f);
  } catch (const yelan::camera::FormatError& e) {
    CHECK(contains(e.what(), "masks/t is not a dataset of numbers of at most 8 bytes"));
    CHECK(contains(e.what(), f));
  }
  const auto r = run_cli({"eval", "--weights", kModel, "--data", f, "--no-floors"});
  CHECK(r.code == 2);
  CHECK(contains(r.err, f));
}

// A 24 KB file `scripts/fuzz recording` made: masks/data declares pictures of about 2^55
// bytes; the mask reader sized its buffer from them (ASan: out of memory) instead of
// holding them to the camera's size.
TEST_CASE("a recording whose masks are not the camera's size is refused before a buffer is sized from them", "[cli]") {
  const std::string f = std::string(YELAN_SOURCE_DIR) + "/tests/data/fuzz-huge-masks.yelan.h5";
  try {
    (void)yelan::camera::sim::read_recording_masks(f, 0, 4);
    FAIL("read_recording_masks accepted " << f);
  } catch (const yelan::camera::FormatError& e) {
    CHECK(contains(e.what(), f));
  }
}
