// `yelan bench events`: TORE update throughput and read-out time, each against a memcpy /
// memset of the same bytes measured in the same run (so figures travel between machines).
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

// args: [--quick] [--json] [--events N] [--reps R] [--k K] [--width W] [--height H]
//       [--file REC] (also replay the first N events of a recording of that size)
//       [--threads T] (also time the read-out split over T OpenMP threads)
// Returns a CLI exit code (0 ok, 2 bad usage).
int run_events_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
