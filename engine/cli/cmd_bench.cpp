// `yelan bench kernels|events ...`: the benchmark harnesses live in benchmarks/.
#include "benchmarks/events/bench_events.h"
#include "benchmarks/kernels/bench_kernels.h"
#include "benchmarks/networks/bench_networks.h"
#include "benchmarks/run/bench_run.h"
#include "benchmarks/run/bench_stream.h"
#include "benchmarks/sim/bench_sim.h"
#include "benchmarks/train/bench_train.h"
#include "engine/cli/args.h"
#include "engine/cli/handlers.h"

namespace yelan::cli {

int cmd_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty()) throw UsageError("bench needs a suite: kernels, events, networks, sim, run or train (see 'yelan bench --help')");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "kernels") return bench::run_kernels_bench(rest, out, err);
  if (args[0] == "events") return bench::run_events_bench(rest, out, err);
  if (args[0] == "networks") return bench::run_networks_bench(rest, out, err);
  if (args[0] == "sim") return bench::run_sim_bench(rest, out, err);
  if (args[0] == "run") return bench::run_pipeline_bench(rest, out, err);
  if (args[0] == "early-exit") return bench::run_early_exit_bench(rest, out, err);
  if (args[0] == "rate-sweep") return bench::run_rate_sweep_bench(rest, out, err);
  if (args[0] == "crop") return bench::run_crop_bench(rest, out, err);
  if (args[0] == "train") return bench::run_train_bench(rest, out, err);
  throw UsageError("unknown benchmark suite '" + args[0] + "' (kernels, events, networks, sim, run, early-exit, rate-sweep, crop, train)");
}

}  // namespace yelan::cli
