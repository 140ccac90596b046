// The `yelan` command: global options, subcommand dispatch, exit codes
// (0 ok, 1 runtime error, 2 bad usage or bad input). main() is a thin wrapper over this
// so tests can drive the whole CLI in-process.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::cli {

enum ExitCode { kOk = 0, kRuntimeError = 1, kUsageError = 2 };

int run(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err);

// Text safe for a terminal: control characters (escape sequences, bells, carriage returns)
// as \xNN; newlines kept.
std::string printable(const std::string& text);

// What `yelan --version` prints: version, ISA chosen, CPU features, library versions.
std::string version_text();

}  // namespace yelan::cli
