// What the benchmark harnesses share: the --threads-list option and the way they reach
// the PyTorch reference scripts.
#pragma once
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cli/args.h"
#include "engine/subprocess.h"
#include "engine/threads.h"

namespace yelan::bench {

// --threads-list "1,2" as thread counts; a bad entry is a usage error.
// The CPU's model name (/proc/cpuinfo), or "unknown CPU": every speed figure names its CPU.
inline std::string cpu_name() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) {
      const auto a = line.find_first_not_of(" \t", line.find(':') + 1);
      return a == std::string::npos ? "unknown CPU" : line.substr(a);
    }
  return "unknown CPU";
}

inline std::vector<int> threads_list(const cli::Args& args, const std::string& fallback = "1,2") {
  std::vector<int> out;
  for (const auto& t : cli::split_list(args.value_or("--threads-list", fallback))) {
    const auto n = parse_thread_count(t);
    if (!n) throw cli::UsageError("--threads-list: '" + t + "' is not a thread count");
    out.push_back(*n);
  }
  return out;
}

// Whether Debian's /usr/bin/python3, the PyTorch reference, imports `modules` ("torch",
// "torch, h5py").
inline bool reference_python_imports(const std::string& modules) {
  return run_program(Program({"/usr/bin/python3", "-c", "import " + modules})).ok();
}

// "1,2": a list as the reference scripts' options take it.
template <class T>
std::string comma_list(const std::vector<T>& v) {
  std::ostringstream o;
  for (std::size_t i = 0; i < v.size(); ++i) o << (i ? "," : "") << v[i];
  return o.str();
}

}  // namespace yelan::bench
