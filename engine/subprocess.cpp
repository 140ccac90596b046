#include "engine/subprocess.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

extern char** environ;

namespace yelan {

namespace {

bool is_executable_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(path.c_str(), X_OK) == 0;
}

// posix_spawn's file actions, freed on every path out.
struct Actions {
  posix_spawn_file_actions_t a;
  Actions() { posix_spawn_file_actions_init(&a); }
  ~Actions() { posix_spawn_file_actions_destroy(&a); }
};

}  // namespace

bool on_path(const std::string& name) {
  if (name.empty()) return false;
  if (name.find('/') != std::string::npos) return is_executable_file(name);
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t at = 0;;) {
    const std::size_t end = dirs.find(':', at);
    const std::string dir = dirs.substr(at, end == std::string::npos ? std::string::npos : end - at);
    if (is_executable_file((dir.empty() ? "." : dir) + "/" + name)) return true;
    if (end == std::string::npos) return false;
    at = end + 1;
  }
}

ProgramResult run_program(const Program& p) {
  ProgramResult r;
  if (p.argv.empty() || !on_path(p.argv[0])) return r;
  int out_pipe[2] = {-1, -1};
  if (p.capture_stdout && ::pipe2(out_pipe, O_CLOEXEC) != 0) return r;
  Actions act;
  posix_spawn_file_actions_addopen(&act.a, 0, p.stdin_path.c_str(), O_RDONLY, 0);
  if (p.capture_stdout)
    posix_spawn_file_actions_adddup2(&act.a, out_pipe[1], 1);
  else
    posix_spawn_file_actions_addopen(&act.a, 1, "/dev/null", O_WRONLY, 0);
  if (!p.show_stderr) posix_spawn_file_actions_addopen(&act.a, 2, "/dev/null", O_WRONLY, 0);
  if (!p.cwd.empty()) posix_spawn_file_actions_addchdir_np(&act.a, p.cwd.c_str());
  std::vector<char*> argv;
  for (const std::string& s : p.argv) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int err = ::posix_spawnp(&pid, argv[0], &act.a, nullptr, argv.data(), environ);
  if (p.capture_stdout) ::close(out_pipe[1]);
  if (err != 0) {
    if (p.capture_stdout) ::close(out_pipe[0]);
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
    if (errno != EINTR) return r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace yelan
