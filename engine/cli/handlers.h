// Handlers of the subcommands, one file engine/cli/cmd_<name>.cpp each; commands.cpp
// lists them. Each takes the arguments after the command name and returns the exit code.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::cli {

// engine/cli/cmd_camera.cpp: live cameras over libusb.
int cmd_devices(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_record(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_events.cpp: event files (camera/io).
int cmd_info(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cmd_convert(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_repr.cpp: representation volumes from event files (camera/repr).
int cmd_repr(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_bench.cpp: benchmark suites (benchmarks/).
int cmd_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_weights.cpp: HDF5 weights files (weights_tools/).
int cmd_weights(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_model.cpp: the C++ networks (`yelan model`, `yelan weights init`).
int cmd_model(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int weights_init(const std::vector<std::string>& args, std::ostream& out);

// engine/cli/cmd_sim.cpp: the motion-to-event simulator (camera/sim).
int cmd_sim(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_train.cpp: the CPU trainer (engine/train).
int cmd_train(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_eval.cpp: evaluation of a weights file on simulated scenes.
int cmd_eval(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// engine/cli/cmd_run.cpp: streaming pose estimation from event files or a camera (engine/run).
int cmd_run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace yelan::cli
