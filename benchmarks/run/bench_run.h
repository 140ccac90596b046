// `yelan bench run [--configs small,paper] [--threads-list 1,2] [--rate 50] [--seconds 2]
// [--beta 0.99] [--weights W1,W2] [--crop-margin PX] [--no-torch] [--json]`: the streaming pipeline (engine/run) on events
// simulated in memory (a dancer, front view, medium light, static background): per-tick time
// split by stage (TORE read-out, stage 1, stage 2), p50/p99, poses per second and the share
// of ticks that ran stage 1, per config and thread count. Without --weights, each config
// runs with random weights: the timing is the same, only the early-exit share differs.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_pipeline_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
