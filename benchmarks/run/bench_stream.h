// `yelan bench early-exit` and `yelan bench rate-sweep`: the streaming pipeline scored on
// test-split scenes (engine/run/stream_eval.h) while one setting varies: the early-exit
// threshold beta (the paper's time/accuracy figure) or the pose rate (20..200 per second
// for a model trained at 50). Prints a table, --json rows, and an SVG/PNG chart.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_early_exit_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int run_rate_sweep_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
