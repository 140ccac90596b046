#pragma once
// Running helper programs (ffmpeg, rsvg-convert, the PyTorch reference scripts) with no
// shell in between: arguments go to the program as they are, so any path works, quotes
// and spaces included, and nothing in a path can be read as a command.
#include <string>
#include <utility>
#include <vector>

namespace yelan {

struct Program {
  Program() = default;
  explicit Program(std::vector<std::string> args) : argv(std::move(args)) {}
  std::vector<std::string> argv;       // argv[0] is looked up on PATH unless it holds a '/'
  std::string cwd;                     // empty: the caller's (argv[0] is still found from the caller's)
  std::string stdin_path = "/dev/null";
  bool capture_stdout = false;         // else stdout goes to /dev/null
  bool show_stderr = false;            // else stderr goes to /dev/null
};

struct ProgramResult {
  bool started = false;  // false: not found, not executable, or its cwd or stdin could not be opened
  int exit_code = -1;    // -1 when killed by a signal
  std::string out;       // stdout, when captured
  std::string error;     // why it did not start, or the signal that ended it
  bool ok() const { return started && exit_code == 0; }
  // "exit code N", "killed by signal S" or why it did not start, for messages.
  std::string why() const;
};

ProgramResult run_program(const Program& p);

// Whether `name` is an executable file on PATH (or at that path, when it holds a '/').
bool on_path(const std::string& name);

}  // namespace yelan
