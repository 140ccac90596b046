// `yelan bench kernels [--quick] [--json] [--isa LIST] [--threads LIST] [--reps N]
// [--chart FILE.svg]`: every network convolution shape, forward and both backwards, per ISA
// and thread count, against the FMA peak measured by the same run.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_kernels_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
