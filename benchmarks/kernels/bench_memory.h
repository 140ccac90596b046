// Memory-bound kernels (BN+ReLU, max pooling, the ConvLSTM point-wise update, softmax) at
// the networks' sizes, each against a memcpy moving the same bytes in the same run; and
// one whole ConvLSTM step (gate conv + point-wise update), forward and backward.
#pragma once
#include <ostream>
#include <vector>

#include "benchmarks/kernels/record.h"
#include "kernels/cpu.h"

namespace yelan::bench {

void bench_memory_bound(kernels::Isa isa, int threads, int reps, std::vector<Record>& out, std::ostream& err);
void bench_convlstm_step(kernels::Isa isa, int threads, int reps, std::vector<Record>& out, std::ostream& err);

}  // namespace yelan::bench
