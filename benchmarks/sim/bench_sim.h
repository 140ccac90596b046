// `yelan bench sim [--duration 2s] [--threads-list 1,2] [--character ben] [--motion 05_04]
// [--view front] [--presets P1,P2] [--json]`: the simulator's speed as simulated seconds per
// wall second (above 1 is faster than real time) for each lighting x background (or each
// preset named), on each thread count,
// with the split between rendering and the pixel model; and the event rate it produces
// against the real DAVIS346 recording in ../shared/data/events (read in the same run).
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_sim_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
