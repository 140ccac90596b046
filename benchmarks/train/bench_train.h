// `yelan bench train [--config small] [--stage pose|mask|both] [--batch 1] [--batches 4]
// [--steps 20] [--threads-list 1] [--sim train] [--json] [--no-torch] [--keep-data FILE]`:
// the trainer's step (zero_grad, forward, loss, backward, Adam, weights_changed) in samples
// (frames) per second, on batches built as the trainer builds them, against PyTorch 1.13
// training the same config from the same initial weights on the same batches (written to
// HDF5), run after ours in a subprocess (benchmarks/torch/train_bench.py).
// `yelan bench train --data DIR [--config C] [--steps 20]`: the whole trainer at one thread,
// data included, reading a dataset on disk against simulating windows afresh (issue 7's
// path): samples/s, samples per CPU-second, the share of step time spent on data.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::bench {

int run_train_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::bench
