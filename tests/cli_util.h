// Running the whole `yelan` command in-process, as tests of every room do.
#pragma once
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

}  // namespace yelan::test
