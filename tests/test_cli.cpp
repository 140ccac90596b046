#include <catch2/catch.hpp>

#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/commands.h"
#include "engine/threads.h"
#include "kernels/cpu.h"
#include "test_util.h"
#include "cli_util.h"

using yelan::cli::Args;
using yelan::cli::UsageError;

namespace {
using Result = yelan::test::CliResult;
Result cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
bool has(const std::string& s, const std::string& what) { return yelan::test::contains(s, what); }
}  // namespace

TEST_CASE("yelan --version names the version, the chosen ISA and the CPU features", "[cli]") {
  Result r = cli({"--version"});
  CHECK(r.code == 0);
  CHECK(has(r.out, "yelan 0."));
  CHECK(has(r.out, std::string("isa: ") + yelan::kernels::isa_name(yelan::kernels::active_isa())));
  CHECK(has(r.out, "cpu features: " + yelan::kernels::cpu_features().describe()));
  CHECK(has(r.out, "HDF5 1."));
  CHECK(has(r.out, "libusb 1."));
}

TEST_CASE("bad usage exits 2 with a one-line message", "[cli]") {
  struct Case { std::vector<std::string> argv; const char* says; };
  for (const Case& c : std::vector<Case>{
           {{}, "usage: yelan"},
           {{"--bogus"}, "unknown option '--bogus'"},
           {{"frobnicate"}, "unknown command 'frobnicate'"},
           {{"--threads", "0", "--version"}, "--threads expects"},
           {{"--threads", "many", "--version"}, "--threads expects"},
           {{"--version", "--threads"}, "--threads needs a value"},
           {{"--isa", "quantum", "--version"}, "--isa expects"},
       }) {
    INFO(c.says);
    Result r = cli(c.argv);
    CHECK(r.code == 2);
    CHECK(has(r.err, c.says));
    CHECK(r.out.empty());
  }
}

TEST_CASE("global --isa forces the kernel ISA and --threads the thread count", "[cli]") {
  yelan::test::IsaGuard guard;
  const int saved_threads = yelan::threads();
  for (auto isa : yelan::test::supported_isas()) {
    Result r = cli({"--isa", yelan::kernels::isa_name(isa), "--threads=1", "--version"});
    CHECK(r.code == 0);
    CHECK(has(r.out, std::string("isa: ") + yelan::kernels::isa_name(isa)));
    CHECK(has(r.out, "threads: 1\n"));
  }
#if defined(__x86_64__)
  Result r = cli({"--isa", "neon", "--version"});
  CHECK(r.code == 2);
  CHECK(has(r.err, "not supported on this CPU"));
#endif
  yelan::set_threads(saved_threads);
}

TEST_CASE("every command answers --help, and one not built yet fails with exit 1", "[cli]") {
  for (const auto& c : yelan::cli::commands()) {
    INFO(c.name);
    Result h = cli({c.name, "--help"});
    CHECK(h.code == 0);
    CHECK(has(h.out, "usage: yelan " + c.name));
    if (!c.handler) {
      Result r = cli({c.name});
      CHECK(r.code == 1);
      CHECK(has(r.err, "not built yet"));
    }
  }
  Result g = cli({"--help"});
  CHECK(g.code == 0);
  for (const auto& c : yelan::cli::commands()) CHECK(has(g.out, "  " + c.name));
}

TEST_CASE("Args parses values, flags and positionals and rejects the rest", "[cli]") {
  Args a("x", {"in.h5", "--rate", "50", "--json", "--out=o.csv", "--", "--literal"},
         {"--rate", "--out"}, {"--json"});
  CHECK(a.positionals() == std::vector<std::string>{"in.h5", "--literal"});
  CHECK(a.flag("--json"));
  CHECK_FALSE(a.flag("--quick"));
  CHECK(a.value("--out") == "o.csv");
  CHECK(a.int_value_or("--rate", 0, 1, 200) == 50);
  CHECK(a.value_or("--missing", "d") == "d");
  CHECK_THROWS_AS(a.int_value_or("--rate", 0, 60, 200), UsageError);
  CHECK_THROWS_AS(a.expect_positionals(3, 3), UsageError);
  CHECK_NOTHROW(a.expect_positionals(1, 2));

  CHECK_THROWS_AS(Args("x", {"--nope"}, {}, {}), UsageError);
  CHECK_THROWS_AS(Args("x", {"--rate"}, {"--rate"}, {}), UsageError);
  CHECK_THROWS_AS(Args("x", {"--rate", "1", "--rate", "2"}, {"--rate"}, {}), UsageError);
  CHECK_THROWS_AS(Args("x", {"--json=1"}, {}, {"--json"}), UsageError);
  CHECK_THROWS_WITH(Args("x", {"--rate", "abc"}, {"--rate"}, {}).int_value_or("--rate", 0, 1, 9),
                    Catch::Contains("'abc'"));
}

TEST_CASE("parse_duration_s reads ms, s, m and h, and refuses the rest naming the flag", "[cli]") {
  using yelan::cli::parse_duration_s;
  CHECK(parse_duration_s("90") == 90);
  CHECK(parse_duration_s("1.5s") == 1.5);
  CHECK(parse_duration_s("500ms") == Approx(0.5));
  CHECK(parse_duration_s("2m") == 120);
  CHECK(parse_duration_s("2min") == 120);
  CHECK(parse_duration_s("1h") == 3600);
  for (const char* bad : {"", "s", "0", "-1s", "1d", "nan", "inf", "1e300h", "2 s", "abc"})
    CHECK_THROWS_WITH(parse_duration_s(bad, "--window"), Catch::Contains("--window expects a positive time"));
}

TEST_CASE("Args::number_or takes finite numbers in range only, naming the option and the range", "[cli]") {
  auto num = [](const std::string& v, double lo, double hi, bool open = false) {
    return Args("x", {"--v", v}, {"--v"}, {}).number_or("--v", -7, lo, hi, open);
  };
  CHECK(num("0.5", 0, 1) == 0.5);
  CHECK(num("1e-3", 0, 1, true) == 1e-3);
  CHECK(Args("x", {}, {"--v"}, {}).number_or("--v", -7, 0, 1) == -7);  // absent: the fallback
  for (const char* bad : {"nan", "inf", "-inf", "1e30", "-1", "2", "abc", "", "0.5x"})
    CHECK_THROWS_WITH(num(bad, 0, 1), Catch::Contains("--v expects a number in [0, 1]"));
  CHECK_THROWS_WITH(num("0", 0, 1, true), Catch::Contains("(0, 1]"));
  CHECK(Args("x", {"--s", "281474976710655"}, {"--s"}, {}).u64_value_or("--s", 1, (1ull << 48) - 1) == (1ull << 48) - 1);
  CHECK_THROWS_WITH(Args("x", {"--s", "99999999999999999999999"}, {"--s"}, {}).u64_value_or("--s", 1, 1000),
                    Catch::Contains("--s expects an integer in [0, 1000]"));
}

TEST_CASE("numbers out of range are refused with exit 2 before any work, naming the flag", "[cli]") {
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", "--weights", M, D, "--height-mm", "nan"}, "--height-mm"},
      {{"run", "--weights", M, D, "--height-mm", "0"}, "--height-mm"},
      {{"run", "--weights", M, D, "--height-mm", "1e30"}, "--height-mm"},
      {{"run", "--weights", M, D, "--depth-mm", "0"}, "--depth-mm"},
      {{"run", "--weights", M, D, "--depth-mm", "-100"}, "--depth-mm"},
      {{"run", "--weights", M, D, "--height-mm", "-5"}, "--height-mm"},
      {{"run", "--weights", M, D, "--height-mm", "inf"}, "--height-mm"},
      {{"run", "--weights", M, D, "--depth-mm", "nan"}, "--depth-mm"},
      {{"run", "--weights", M, D, "--depth-mm", "1e30"}, "--depth-mm"},
      {{"run", "--weights", M, D, "--beta", "nan"}, "--beta"},
      {{"run", "--weights", M, D, "--beta", "2"}, "--beta"},
      {{"run", "--weights", M, D, "--beta", "-1"}, "--beta"},
      {{"run", "--weights", M, D, "--rate", "inf"}, "--rate"},
      {{"eval", "--weights", M, "--sim", "test", "--seconds", "0"}, "--seconds"},
      {{"eval", "--weights", M, "--sim", "test", "--seconds", "nan"}, "--seconds"},
      {{"eval", "--weights", M, "--sim", "test", "--seconds", "-1"}, "--seconds"},
      {{"eval", "--weights", M, "--sim", "test", "--low-light-dn", "0"}, "--low-light-dn"},
      {{"eval", "--weights", M, "--sim", "test", "--low-light-dn", "nan"}, "--low-light-dn"},
      {{"eval", "--weights", M, "--data", "/tmp", "--low-light-dn", "4"}, "--low-light-dn"},
      {{"sim", "--dataset", "/tmp/x", "--train", "1", "--low-light-dn", "-4"}, "--low-light-dn"},
      {{"train", "--stage", "pose", "--config", "micro", "--sim", "train", "-o", "/tmp/x", "--lr", "-1"}, "--lr"},
      {{"train", "--stage", "pose", "--config", "micro", "--sim", "train", "-o", "/tmp/x", "--lr", "abc"}, "--lr"},
      {{"train", "--stage", "pose", "--config", "micro", "--sim", "train", "-o", "/tmp/x", "--max-minutes", "0"},
       "--max-minutes"},
      {{"train", "--stage", "pose", "--config", "micro", "--sim", "train", "-o", "/tmp/x", "--checkpoint-minutes", "0"},
       "--checkpoint-minutes"},
      {{"sim", "--preset", "front-high-static", "-o", "/tmp/x.yelan.h5", "--seed", "99999999999999999999999"}, "--seed"},
  };
  for (const auto& [argv, flag] : cases) {
    INFO(argv[0] << " " << argv[argv.size() - 2] << " " << argv.back());
    const Result r = cli(argv);
    CHECK(r.code == 2);
    CHECK(has(r.err, flag));
    CHECK_FALSE(has(r.err, "stod"));
    CHECK_FALSE(has(r.err, "stoull"));
  }
}

TEST_CASE("eval --scenes M limits any scene list to M seeded picks", "[cli]") {
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const Result r = cli({"eval", "--weights", M, "--sim", "train", "--scenes", "1", "--seconds", "0.04", "--history", "0.1",
                        "--no-floors"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, ", 1 scenes,"));
}

TEST_CASE("run refuses outputs it cannot write or that are its input, before any work", "[cli]") {
  yelan::test::CliTempDir d("run-outputs");
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const std::string in = d / "in.yelan.h5";
  std::filesystem::copy_file(std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5", in);
  const std::string before = yelan::test::slurp(in);
  const Result same = cli({"run", "--weights", M, in, "--out", in});
  CHECK(same.code == 2);
  CHECK(has(same.err, "--out " + in + " is an input"));
  CHECK(yelan::test::slurp(in) == before);  // the input untouched
  for (const char* flag : {"--out", "--stats-json"}) {
    INFO(flag);
    const std::string ext = std::string(flag) == "--out" ? ".csv" : ".json";
    const Result proc = cli({"run", "--weights", M, in, flag, "/proc/x" + ext});
    CHECK(proc.code == 2);
    CHECK(has(proc.err, "cannot write in /proc"));
    const Result nodir = cli({"run", "--weights", M, in, flag, d / ("nodir/x" + ext)});
    CHECK(nodir.code == 2);
    CHECK(has(nodir.err, "no directory"));
    CHECK(nodir.out.empty());  // refused before inference: no run report
  }
}

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

TEST_CASE("Ctrl-C or SIGTERM during sim, convert or repr leaves no temporary file", "[cli]") {
  yelan::test::CliTempDir d("signals");
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  const std::vector<std::pair<std::vector<std::string>, std::string>> commands = {
      {{"sim", "--preset", "front-high-dynamic", "--duration", "60s", "-o", d / "s.yelan.h5", "--quiet"}, "s.yelan.h5"},
      {{"convert", D, d / "c.txt"}, "c.txt"},
      {{"repr", "--type", "tore", "--fps", "2000", D, d / "r.h5"}, "r.h5"},
  };
  auto temps = [&](const std::string& out) {
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator(d.p)) n += e.path().filename().string().rfind(out + ".tmp-", 0) == 0;
    return n;
  };
  for (const auto& [cmd, out] : commands)
    for (const int sig : {SIGINT, SIGTERM}) {
      INFO(cmd[0] << " signal " << sig);
      const pid_t child = yelan::test::spawn(YELAN_BINARY, cmd);
      REQUIRE(child > 0);
      // The signal goes only once the command is writing (its temporary file exists): one
      // that finished first, or never began writing, fails the test instead of passing it.
      int status = 0;
      bool exited = false, writing = false;
      for (int i = 0; i < 120000 && !exited && !writing; ++i) {  // up to 2 min: sanitizer builds are slow
        writing = temps(out) > 0;
        exited = !writing && ::waitpid(child, &status, WNOHANG) == child;
        if (!writing && !exited) ::usleep(1000);
      }
      if (!exited) {
        ::kill(child, writing ? sig : SIGKILL);
        REQUIRE(::waitpid(child, &status, 0) == child);
      }
      REQUIRE(writing);
      // The default action after the cleanup: the command dies by the signal, as if unhandled.
      CHECK((WIFSIGNALED(status) && WTERMSIG(status) == sig));
      CHECK_FALSE(std::filesystem::exists(d / out));  // interrupted before it completed
      CHECK(temps(out) == 0);
      for (const auto& e : std::filesystem::directory_iterator(d.p)) std::filesystem::remove_all(e.path());
    }
}

TEST_CASE("text from files is shown escaped, and bad input is exit 2 for every command", "[cli]") {
  yelan::test::CliTempDir d("escaped");
  {
    std::ofstream f(d / "esc.raw", std::ios::binary);
    f << "% evt \x1b]0;pwned\x07\x1b[31mRED\n% end\n";
  }
  const Result r = cli({"info", d / "esc.raw"});
  CHECK(r.code == 2);
  CHECK(has(r.err, "\\x1b]0;pwned\\x07\\x1b[31mRED"));
  CHECK_FALSE(has(r.err, "\x1b"));
  CHECK_FALSE(has(r.err, "\x07"));
  CHECK(yelan::cli::printable("a\rb\x7f\n") == "a\\x0db\\x7f\n");
  // A corrupt weights file and an event file passed as weights: bad input (2) for run too.
  std::ofstream(d / "junk.h5") << "not HDF5 at all";
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  CHECK(cli({"run", "--weights", d / "junk.h5", D}).code == 2);
  CHECK(cli({"run", "--weights", D, D}).code == 2);
  CHECK(cli({"weights", "inspect", d / "junk.h5"}).code == 2);
}

TEST_CASE("messages name the file and quote attributes whole", "[cli]") {
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const Result w = cli({"run", "--weights", D, D});
  CHECK(w.code == 2);
  CHECK(has(w.err, "format is 'yelan-recording', expected 'yelan-weights'"));
  CHECK(has(w.err, D));
  const Result f = cli({"model", "forward", "--weights", M, "--input", "nope.h5", "--output", "/tmp/never.h5"});
  CHECK(f.code == 2);
  CHECK(has(f.err, "--input nope.h5: no such file"));
}

TEST_CASE("Ctrl-C during run on a file writes every pose computed so far, and its pictures", "[cli]") {
  yelan::test::CliTempDir d("run-signal");
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  std::filesystem::create_directories(d / "viz");
  const std::vector<std::string> args = {"run", "--weights", M, D, "--out", d / "p.csv", "--viz", d / "viz",
                                         "--no-early-exit", "--threads", "1"};
  const pid_t child = yelan::test::spawn(YELAN_BINARY, args);
  REQUIRE(child > 0);
  auto pngs = [&] {
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator(d.p / "viz")) n += e.path().extension() == ".png";
    return n;
  };
  int status = 0;
  bool finished = false;
  for (int i = 0; i < 24000 && pngs() < 4; ++i) {  // up to 2 min: sanitizer builds are slow
    if (::waitpid(child, &status, WNOHANG) == child) {
      finished = true;
      break;
    }
    ::usleep(5000);
  }
  if (!finished) {
    ::kill(child, SIGINT);
    REQUIRE(::waitpid(child, &status, 0) == child);
    CHECK(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
  }
  REQUIRE(std::filesystem::exists(d / "p.csv"));
  std::istringstream csv(yelan::test::slurp(d / "p.csv"));
  int rows = -1;  // the header
  for (std::string l; std::getline(csv, l);) ++rows;
  CHECK(rows >= 1);
  CHECK(rows >= pngs() - 1);  // every pose computed (each has its picture) is in the file
  for (const auto& e : std::filesystem::directory_iterator(d.p / "viz"))
    CHECK(e.path().string().find(".tmp-") == std::string::npos);
}

TEST_CASE("every shipped model verifies against its config's manifest", "[cli]") {
  const std::string models = std::string(YELAN_SOURCE_DIR) + "/models/";
  // The default's stage 1 is at width 0.375 since 2026-11-29 (mask-s15): its networks' config,
  // by name and as the file it was trained under (the shipped -presence config differs only
  // in roles and run settings, which a manifest does not hold).
  const std::string configs = std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/";
  for (const auto& [file, config] : {std::pair<std::string, std::string>{"default.h5", "small-mask0.375-pose0.125"},
                                     {"default.h5", configs + "small-mask0.375-pose0.125.json"},
                                     {"small-first.h5", "small"}}) {
    const Result r = cli({"weights", "verify", models + file, "--config", config});
    INFO(file << " " << config << ": " << r.err);
    CHECK(r.code == 0);
    CHECK(has(r.out, "ok: "));
  }
}

TEST_CASE("the shipped models carry a checksum on their tensors", "[cli]") {
  for (const char* m : {"default.h5", "small-first.h5"}) {
    const std::string path = std::string(YELAN_SOURCE_DIR) + "/models/" + m;
    INFO(path);
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    REQUIRE(f >= 0);
    for (const char* t : {"/mask/down1.maxpool_conv.1.double_conv.0.weight", "/mask/down1.maxpool_conv.1.double_conv.1.bias"}) {
      const hid_t ds = H5Dopen2(f, t, H5P_DEFAULT);
      REQUIRE(ds >= 0);
      CHECK(H5Aexists(ds, "fnv1a64") > 0);
      H5Dclose(ds);
    }
    H5Fclose(f);
  }
}

TEST_CASE("event timestamps beyond +-2^60 us: info and run exit 2", "[cli]") {
  yelan::test::CliTempDir d("big-times");
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  std::ofstream(d / "big.txt") << "# geometry 346x260\n-9000000000000 1 1 1\n9000000000000 2 2 0\n";  // s: +-9e18 us
  const std::vector<std::vector<std::string>> commands = {{"info", d / "big.txt"},
                                                          {"run", "--weights", M, d / "big.txt", "--out", d / "o.csv"}};
  for (const auto& argv : commands) {
    const Result r = cli(argv);
    INFO(argv[0] << ": " << r.err);
    CHECK(r.code == 2);
    CHECK(has(r.err, d / "big.txt"));
    CHECK(has(r.err, "is outside +-2^60 us"));
  }
}

#include "weights_tools/weights_file.h"

TEST_CASE("weights whose tensors do not fit their config: exit 2 naming the file and the tensor", "[cli]") {
  yelan::test::CliTempDir d("misfit");
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  yelan::weights::Weights w = yelan::weights::load_weights(M);
  std::string key;
  for (auto& [name, t] : w.groups.at("pose"))
    if (t.shape.size() > 1) {  // flattened: the same values in a shape the network does not have
      key = name;
      t.shape = {yelan::weights::element_count(t.shape)};
      break;
    }
  REQUIRE_FALSE(key.empty());
  yelan::weights::save_weights(d / "misfit.h5", w);
  const Result r = cli({"run", "--weights", d / "misfit.h5", D, "--out", d / "o.csv"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(has(r.err, d / "misfit.h5" + ": /pose does not fit"));
  CHECK(has(r.err, "mis-shaped: " + key + " is ["));
  CHECK_FALSE(std::filesystem::exists(d / "o.csv"));
}

TEST_CASE("a byte flipped inside a tensor's data: its checksum catches it, exit 2 naming the tensor", "[cli]") {
  yelan::test::CliTempDir d("flipped");
  const std::string M = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  const std::string D = std::string(YELAN_SOURCE_DIR) + "/data/demo/lena-93_03-front-high-static.yelan.h5";
  std::filesystem::copy_file(M, d / "flipped.h5");
  std::string tensor;
  haddr_t at = HADDR_UNDEF;
  {
    const yelan::weights::WeightsReader r(M);
    for (const auto& t : r.tensors("pose"))
      if (yelan::weights::element_count(t.shape) >= 64) {
        tensor = t.name;
        break;
      }
    REQUIRE_FALSE(tensor.empty());
    const hid_t f = H5Fopen(M.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    REQUIRE(f >= 0);
    const hid_t ds = H5Dopen2(f, ("/pose/" + tensor).c_str(), H5P_DEFAULT);
    REQUIRE(ds >= 0);
    at = H5Dget_offset(ds);  // contiguous storage: the data's first byte in the file
    H5Dclose(ds);
    H5Fclose(f);
  }
  REQUIRE(at != HADDR_UNDEF);
  {
    std::fstream f(d / "flipped.h5", std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(std::streamoff(at + 4 * 17 + 1));  // a byte inside the 18th value
    const char c = char(f.get());
    f.seekp(std::streamoff(at + 4 * 17 + 1));
    f.put(char(c ^ 0x10));
    REQUIRE(f.good());
  }
  const Result r = cli({"run", "--weights", d / "flipped.h5", D, "--out", d / "o.csv"});
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK(has(r.err, d / "flipped.h5"));
  CHECK(has(r.err, "tensor /pose/" + tensor + ": checksum mismatch"));
  CHECK_FALSE(std::filesystem::exists(d / "o.csv"));
}

#include <algorithm>

#include "engine/cli/vet_recordings.h"

TEST_CASE("recordings vetted up front: one line saying how many children ran, the stream's number format kept", "[cli]") {
  yelan::test::CliTempDir d("vet-up-front");
  std::vector<std::string> recs;
  for (const char* n : {"a.yelan.h5", "b.yelan.h5", "c.yelan.h5"}) {
    recs.push_back(d / n);
    std::ofstream(recs.back()) << "not HDF5: an ordinary error, left to the real read";
  }
  std::ostringstream err;
  yelan::cli::vet_recordings_up_front(recs, err);
  const std::string line = err.str();
  CHECK(yelan::test::contains(line, "vetted 3 of 3 recordings"));
  CHECK(std::count(line.begin(), line.end(), '\n') == 1);
  err << 0.123456 << " " << 2.0;  // what the caller prints next keeps its own precision
  CHECK(yelan::test::contains(err.str(), " s\n0.123456 2"));
}
