#include "camera/io/untrusted.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>
#include <tuple>

#include "camera/io/format_error.h"

#if defined(__SANITIZE_ADDRESS__)
#define YELAN_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define YELAN_ASAN 1
#endif
#endif

namespace yelan::camera {

namespace {

bool g_child = false;
std::mutex g_mutex;
std::set<std::tuple<dev_t, ino_t, off_t, long long>> g_passed;

std::tuple<dev_t, ino_t, off_t, long long> identity(const struct stat& st) {
  return {st.st_dev, st.st_ino, st.st_size, (long long)st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec};
}

// The process's address space now, in bytes (0 if unknown). A child inherits all of it, so
// its limit is this plus the budget: a large caller (a training) must not fail every file.
unsigned long long address_space_bytes() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char buf[64] = {};
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  return n > 0 ? std::strtoull(buf, nullptr, 10) * static_cast<unsigned long long>(::sysconf(_SC_PAGESIZE)) : 0;
}

}  // namespace

bool vetting_child() { return g_child; }

void forget_vetted_files() {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_passed.clear();
}

void vet_in_child(const std::string& path, const std::function<void()>& read_all, const UntrustedLimits& limits) {
  if (g_child) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;  // the real read says what is wrong
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    if (g_passed.count(identity(st))) return;
  }
  const unsigned long long memory_limit = address_space_bytes() + limits.memory_bytes;
  const pid_t pid = ::fork();
  if (pid < 0) return;  // cannot isolate: read as before rather than refuse
  if (pid == 0) {
    g_child = true;
    if (!std::getenv("YELAN_VET_STDERR")) {  // libhdf5's and the sanitizers' words stay out of the user's way
      const int null = ::open("/dev/null", O_WRONLY);
      if (null >= 0) ::dup2(null, 2), ::dup2(null, 1);
    }
#ifndef YELAN_ASAN  // ASan reserves terabytes of address space; its own reports bound the damage there
    const rlimit mem{memory_limit, memory_limit};
    ::setrlimit(RLIMIT_AS, &mem);
#endif
    const rlimit cpu{limits.seconds, limits.seconds + 1};  // SIGXCPU at the soft limit, SIGKILL a second later
    ::setrlimit(RLIMIT_CPU, &cpu);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    int code = 0;
    try {
      read_all();
    } catch (const std::bad_alloc&) {
      code = 4;  // the memory limit
    } catch (...) {
      code = 3;  // an ordinary error: the parent's own read reports it in full
    }
    ::_exit(code);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return;
  if (WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3)) {
    if (WEXITSTATUS(status) == 0) {
      std::lock_guard<std::mutex> lock(g_mutex);
      g_passed.insert(identity(st));
    }
    return;
  }
  std::string why;
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    why = sig == SIGXCPU || sig == SIGKILL ? "reading it took more than " + std::to_string(limits.seconds) + " s of CPU"
                                           : std::string("libhdf5 crashed reading it (") + ::strsignal(sig) + ")";
  } else if (WEXITSTATUS(status) == 4) {
    why = "reading it needs more than " + std::to_string(limits.memory_bytes >> 20) + " MiB";
  } else {
    why = "reading it failed in libhdf5 (exit " + std::to_string(WEXITSTATUS(status)) + ", a sanitizer report?)";
  }
  throw FormatError(path, 0, "corrupt HDF5 file: " + why);
}

}  // namespace yelan::camera
