// Running the whole `yelan` command in-process, as tests of every room do.
#pragma once
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cli/cli.h"

namespace yelan::test {

// The real binary started as a child process (its output to /dev/null, its stderr to
// `stderr_path` if given), for tests that send it signals; returns the child's pid. With a
// `gate` (a pipe's read end), the child waits for a byte on it before it starts the binary,
// so that the test can first prepare files named after its pid.
inline pid_t spawn(const std::string& binary, const std::vector<std::string>& args,
                   const std::string& stderr_path = "/dev/null", int gate = -1) {
  const pid_t child = ::fork();
  if (child != 0) return child;
  char byte;
  if (gate >= 0 && ::read(gate, &byte, 1) != 1) ::_exit(125);
  std::vector<char*> argv = {const_cast<char*>(binary.c_str())};
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  if (!std::freopen("/dev/null", "w", stdout) || !std::freopen(stderr_path.c_str(), "w", stderr)) ::_exit(126);
  ::execv(binary.c_str(), argv.data());
  ::_exit(127);
}

// A child (or the real binary) run to its end, as a shell would: its exit code, 128 + the
// signal that killed it, or -1 when it ran longer than `seconds` (it is killed then).
inline int wait_child(pid_t child, int seconds) {
  if (child < 0) return -2;
  int status = 0;
  for (int waited_ms = 0; ::waitpid(child, &status, WNOHANG) != child; waited_ms += 10) {
    if (waited_ms >= seconds * 1000) {
      ::kill(child, SIGKILL);
      ::waitpid(child, &status, 0);
      return -1;
    }
    ::usleep(10000);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

inline int run_binary(const std::string& binary, const std::vector<std::string>& args, int seconds,
                      const std::string& stderr_path = "/dev/null") {
  return wait_child(spawn(binary, args, stderr_path), seconds);
}

struct CliResult {
  int code;
  std::string out, err;
};

inline CliResult run_cli(std::vector<std::string> argv) {
  std::ostringstream out, err;
  const int code = yelan::cli::run(argv, out, err);
  return {code, out.str(), err.str()};
}

inline bool contains(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

inline std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A fresh folder under the system's temp directory, removed with everything in it.
struct CliTempDir {
  std::filesystem::path p;
  explicit CliTempDir(const std::string& tag)
      : p(std::filesystem::temp_directory_path() / ("yelan-" + tag + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(p);
  }
  ~CliTempDir() { std::filesystem::remove_all(p); }
  std::string operator/(const std::string& f) const { return (p / f).string(); }
};

}  // namespace yelan::test
