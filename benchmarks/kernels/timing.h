// Timing helpers for benchmarks: medians of repeated runs, each run long enough to
// swamp timer resolution.
#pragma once
#include <algorithm>
#include <chrono>
#include <vector>

namespace yelan::bench {

inline double now_seconds() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

// Seconds per call of f: median over `reps` runs of at least `min_run_s` each.
template <class F>
double median_seconds_per_call(F&& f, int reps, double min_run_s) {
  f();  // warm caches, page in buffers
  std::vector<double> runs;
  for (int r = 0; r < reps; ++r) {
    int calls = 0;
    const double t0 = now_seconds();
    double t1;
    do {
      f();
      ++calls;
      t1 = now_seconds();
    } while (t1 - t0 < min_run_s);
    runs.push_back((t1 - t0) / calls);
  }
  std::nth_element(runs.begin(), runs.begin() + runs.size() / 2, runs.end());
  return runs[runs.size() / 2];
}

}  // namespace yelan::bench
