// Runs benchmarks/torch/conv_bench.py (Debian's PyTorch 1.13 under /usr/bin/python3) on
// the same shapes, after our own timings, so the two thread pools never share the cores.
#pragma once
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "benchmarks/kernels/shapes.h"

namespace yelan::bench {

// (where, op, threads) -> milliseconds
using TorchTimes = std::map<std::tuple<std::string, std::string, int>, double>;

// Empty, with `why` set, when PyTorch cannot be run here.
TorchTimes torch_conv_times(const std::vector<ConvCase>& cases, const std::vector<int>& threads, int reps,
                            std::string* why);

}  // namespace yelan::bench
