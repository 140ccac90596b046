// What the benchmark harnesses share: the --threads-list option.
#pragma once
#include <string>
#include <vector>

#include "engine/cli/args.h"
#include "engine/threads.h"

namespace yelan::bench {

// --threads-list "1,2" as thread counts; a bad entry is a usage error.
inline std::vector<int> threads_list(const cli::Args& args, const std::string& fallback = "1,2") {
  std::vector<int> out;
  for (const auto& t : cli::split_list(args.value_or("--threads-list", fallback))) {
    const auto n = parse_thread_count(t);
    if (!n) throw cli::UsageError("--threads-list: '" + t + "' is not a thread count");
    out.push_back(*n);
  }
  return out;
}

}  // namespace yelan::bench
