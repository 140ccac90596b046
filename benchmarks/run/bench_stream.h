// `yelan bench early-exit`, `rate-sweep` and `crop`: the streaming pipeline scored on
// test-split scenes (engine/run/stream_eval.h) while one setting varies: the early-exit
// threshold beta (the paper's time/accuracy figure), the pose rate (20..200 per second
// for a model trained at 50) or the margin of stage 2's crop around the mask. Prints a table, --json rows, and an SVG/PNG chart.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_early_exit_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int run_rate_sweep_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
// The crop margin of stage 2's head (0: the whole frame), as a sweep like the others.
int run_crop_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
