// `yelan bench networks [--configs paper,small,tiny] [--threads-list 1,2] [--window W]
// [--reps N] [--json] [--no-torch]`: both networks per frame, inference (BN with running
// statistics, Winograd where it applies) and training (batch statistics, forward + loss +
// backward), with the memory they hold at peak; PyTorch 1.13 on the same configs after.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_networks_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
