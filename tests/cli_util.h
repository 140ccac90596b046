// Running the whole `yelan` command in-process, as tests of every room do.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cli/cli.h"

namespace yelan::test {

struct CliResult {
  int code;
  std::string out, err;
};

inline CliResult run_cli(std::vector<std::string> argv) {
  std::ostringstream out, err;
  const int code = yelan::cli::run(argv, out, err);
  return {code, out.str(), err.str()};
}

inline bool contains(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A fresh folder under the system's temp directory, removed with everything in it.
struct CliTempDir {
  std::filesystem::path p;
  explicit CliTempDir(const std::string& tag)
      : p(std::filesystem::temp_directory_path() / ("yelan-" + tag + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(p);
  }
  ~CliTempDir() { std::filesystem::remove_all(p); }
  std::string operator/(const std::string& f) const { return (p / f).string(); }
};

}  // namespace yelan::test
