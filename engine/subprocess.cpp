#include "engine/subprocess.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

extern char** environ;

namespace yelan {

namespace {

bool is_executable_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

// The program's absolute path, resolved in the caller's directory (so a cwd for the child
// does not change which program runs); empty when there is none.
std::string find_program(const std::string& name) {
  if (name.empty()) return {};
  std::error_code ec;
  if (name.find('/') != std::string::npos) {
    const std::string abs = std::filesystem::absolute(name, ec).string();
    return !ec && is_executable_file(abs) ? abs : std::string();
  }
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t at = 0;;) {
    const std::size_t end = dirs.find(':', at);
    const std::string dir = dirs.substr(at, end == std::string::npos ? std::string::npos : end - at);
    const std::string abs = std::filesystem::absolute(std::filesystem::path(dir.empty() ? "." : dir) / name, ec).string();
    if (!ec && is_executable_file(abs)) return abs;
    if (end == std::string::npos) return {};
    at = end + 1;
  }
}

// posix_spawn's file actions, freed on every path out.
struct Actions {
  posix_spawn_file_actions_t a;
  Actions() { posix_spawn_file_actions_init(&a); }
  ~Actions() { posix_spawn_file_actions_destroy(&a); }
};

}  // namespace

std::string ProgramResult::why() const {
  if (!started) return error;
  if (exit_code >= 0) return "exit code " + std::to_string(exit_code);
  return error;
}

bool on_path(const std::string& name) { return !find_program(name).empty(); }

ProgramResult run_program(const Program& p) {
  ProgramResult r;
  const std::string exe = p.argv.empty() ? std::string() : find_program(p.argv[0]);
  if (exe.empty()) {
    r.error = p.argv.empty() ? "no program named" : p.argv[0] + ": not found, or not an executable file";
    return r;
  }
  // The stdin and the cwd are checked here, not left to the child: not every posix_spawn
  // (qemu-user's, for one) reports a child that failed to open them.
  if (!p.cwd.empty()) {
    struct stat st {};
    const char* bad_dir = ::stat(p.cwd.c_str(), &st) != 0 ? std::strerror(errno)
                          : !S_ISDIR(st.st_mode)           ? "not a directory"
                          : ::access(p.cwd.c_str(), X_OK) != 0 ? std::strerror(errno)
                                                             : nullptr;
    if (bad_dir) {
      r.error = "cannot start " + exe + " in " + p.cwd + ": " + bad_dir;
      return r;
    }
  }
  const int in = ::open(p.stdin_path.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) {
    r.error = "cannot start " + exe + " with stdin " + p.stdin_path + ": " + std::strerror(errno);
    return r;
  }
  int out_pipe[2] = {-1, -1};
  if (p.capture_stdout && ::pipe2(out_pipe, O_CLOEXEC) != 0) {
    r.error = std::string("cannot make a pipe: ") + std::strerror(errno);
    ::close(in);
    return r;
  }
  Actions act;
  int bad = posix_spawn_file_actions_adddup2(&act.a, in, 0);
  if (p.capture_stdout)
    bad = bad ? bad : posix_spawn_file_actions_adddup2(&act.a, out_pipe[1], 1);
  else
    bad = bad ? bad : posix_spawn_file_actions_addopen(&act.a, 1, "/dev/null", O_WRONLY, 0);
  if (!p.show_stderr) bad = bad ? bad : posix_spawn_file_actions_addopen(&act.a, 2, "/dev/null", O_WRONLY, 0);
  if (!p.cwd.empty()) bad = bad ? bad : posix_spawn_file_actions_addchdir_np(&act.a, p.cwd.c_str());
  std::vector<char*> argv;
  for (const std::string& s : p.argv) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  // glibc reports a stdin or cwd the child could not open as the spawn's own error.
  const int err = bad ? bad : ::posix_spawn(&pid, exe.c_str(), &act.a, nullptr, argv.data(), environ);
  ::close(in);
  if (p.capture_stdout) ::close(out_pipe[1]);
  if (err != 0) {
    if (p.capture_stdout) ::close(out_pipe[0]);
    r.error = "cannot start " + exe + " (stdin " + p.stdin_path + (p.cwd.empty() ? "" : ", in " + p.cwd) +
              "): " + std::strerror(err);
    return r;
  }
  r.started = true;
  if (p.capture_stdout) {
    char buf[4096];
    for (;;) {
      const ssize_t n = ::read(out_pipe[0], buf, sizeof buf);
      if (n > 0) r.out.append(buf, std::size_t(n));
      else if (n == 0 || errno != EINTR) break;
    }
    ::close(out_pipe[0]);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      r.error = std::string("lost ") + exe + ": " + std::strerror(errno);
      return r;
    }
  if (WIFEXITED(status)) {
    r.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.error = "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  }
  return r;
}

}  // namespace yelan
