#include "camera/io/untrusted.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>
#include <vector>

#include "camera/io/asan.h"
#include "camera/io/format_error.h"

namespace yelan::camera {

namespace {

// The status-change time is part of a file's identity: unlike the modification time, no
// user call sets it, so a file rewritten after it passed never looks like the one that did.
using Identity = std::tuple<unsigned long long, unsigned long long, long long, long long, long long>;

bool g_child = false;
std::mutex g_mutex;
std::set<Identity> g_passed;
// The vetting cache on disk (cache_path_locked()): loaded once, appended to by each pass.
bool g_cache_loaded = false;
std::optional<std::string> g_cache_override;  // use_vet_cache's path, over the environment's

long long ns(const struct timespec& t) { return (long long)t.tv_sec * 1000000000LL + t.tv_nsec; }

Identity identity(const struct stat& st) {
  return {(unsigned long long)st.st_dev, (unsigned long long)st.st_ino, (long long)st.st_size, ns(st.st_mtim), ns(st.st_ctim)};
}

// A file is remembered on disk only when its status changed this long before it was read:
// status-change times are coarse (a kernel tick), and a file rewritten within one tick of
// its vetting would otherwise keep the identity of the file that passed.
constexpr long long kSettledNs = 2'000'000'000LL;

std::string cache_path_locked() {
  if (g_cache_override) return *g_cache_override;
  const char* env = std::getenv("YELAN_VET_CACHE");
  if (env) return std::string(env) == "off" ? std::string() : std::string(env);
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg == '/') return std::string(xdg) + "/yelan/vetted-files";
  if (const char* home = std::getenv("HOME"); home && *home == '/') return std::string(home) + "/.cache/yelan/vetted-files";
  return {};
}

constexpr const char* kCacheTag = "yelan-vetted-v1";
constexpr std::uintmax_t kCacheMaxBytes = 8u << 20;  // ~100k files; past it the cache starts afresh

// Lines "yelan-vetted-v1 dev inode size mtime_ns ctime_ns"; anything else is skipped (a
// cache is never a reason to fail, only a reason to skip a child).
void load_cache_locked() {
  if (g_cache_loaded) return;
  g_cache_loaded = true;
  const std::string path = cache_path_locked();
  if (path.empty()) return;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return;
  if (size > kCacheMaxBytes) {
    std::filesystem::remove(path, ec);
    return;
  }
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string tag;
    unsigned long long dev = 0, ino = 0;
    long long bytes = 0, mtime = 0, ctime = 0;
    if (f >> tag >> dev >> ino >> bytes >> mtime >> ctime && tag == kCacheTag) g_passed.insert({dev, ino, bytes, mtime, ctime});
  }
}

// One line in one append: concurrent trainings interleave whole lines.
void remember_on_disk_locked(const Identity& id) {
  const std::string path = cache_path_locked();
  if (path.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) return;
  char line[160];
  const int n = std::snprintf(line, sizeof line, "%s %llu %llu %lld %lld %lld\n", kCacheTag, std::get<0>(id), std::get<1>(id),
                              std::get<2>(id), std::get<3>(id), std::get<4>(id));
  if (n > 0 && n < int(sizeof line)) (void)!::write(fd, line, std::size_t(n));
  ::close(fd);
}

long long now_ns() {
  struct timespec t {};
  ::clock_gettime(CLOCK_REALTIME, &t);
  return ns(t);
}

// Field `field` of /proc/self/statm in bytes (0: the address space, 1: resident; 0 if unknown).
unsigned long long statm_bytes(int field) {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char buf[128] = {};
  const ssize_t n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (n <= 0) return 0;
  char* p = buf;
  unsigned long long pages = 0;
  for (int f = 0; f <= field; ++f) pages = std::strtoull(p, &p, 10);
  return pages * static_cast<unsigned long long>(::sysconf(_SC_PAGESIZE));
}
// The process's address space now. A child inherits all of it, so its limit is this plus the
// budget: a large caller (a training) must not fail every file.
unsigned long long address_space_bytes() { return statm_bytes(0); }

// A child that failed with an ordinary error after growing by more than this is not read
// again in the process: libhdf5 converts a variable-length string by its declared length, so
// a 10 kB file can ask for 2 GB (a fuzzer found one), and the second read would take it again
// to say why the file is bad. A bad file's own data can need several times its size.
unsigned long long refused_growth_bytes(off_t file_bytes) {
  return std::max<unsigned long long>(512ull << 20, 16ull * static_cast<unsigned long long>(std::max<off_t>(file_bytes, 0)));
}

}  // namespace

bool vetting_child() { return g_child; }

void forget_vetted_files() {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_passed.clear();
  g_cache_loaded = true;  // the disk's entries are forgotten too, for the rest of this process
}

void use_vet_cache(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_cache_override = path;
  g_passed.clear();
  g_cache_loaded = false;
}

namespace {

// vet_in_child, saying whether a child ran.
bool vet_once(const std::string& path, const std::function<void()>& read_all, const UntrustedLimits& limits) {
  if (g_child) return false;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;  // the real read says what is wrong
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    load_cache_locked();
    if (g_passed.count(identity(st))) return false;
  }
  const bool settled = now_ns() - ns(st.st_ctim) >= kSettledNs;
  const unsigned long long memory_limit = address_space_bytes() + limits.memory_bytes;
  const unsigned long long resident = statm_bytes(1);
  const pid_t pid = ::fork();
  if (pid < 0) return false;  // cannot isolate: read as before rather than refuse
  if (pid == 0) {
    g_child = true;
    if (!std::getenv("YELAN_VET_STDERR")) {  // libhdf5's and the sanitizers' words stay out of the user's way
      const int null = ::open("/dev/null", O_WRONLY);
      if (null >= 0) ::dup2(null, 2), ::dup2(null, 1);
    }
    if (!kUnderAsan) {  // ASan reserves terabytes of address space; its own reports bound the damage there
      const rlimit mem{memory_limit, memory_limit};
      ::setrlimit(RLIMIT_AS, &mem);
    }
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
  struct rusage usage {};
  while (::wait4(pid, &status, 0, &usage) < 0)
    if (errno != EINTR) return true;
  // The child starts resident as the caller was (its pages shared until written).
  const unsigned long long peak = static_cast<unsigned long long>(std::max(usage.ru_maxrss, 0L)) * 1024ull;
  const unsigned long long grew = peak > resident ? peak - resident : 0;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 3 && resident > 0 && grew > refused_growth_bytes(st.st_size))
    throw FormatError(path, 0, "corrupt HDF5 file: reading it took " + std::to_string(grew >> 20) + " MiB for a file of " +
                                   std::to_string(st.st_size) + " bytes before it failed (not read again)");
  if (WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3)) {
    if (WEXITSTATUS(status) == 0) {
      std::lock_guard<std::mutex> lock(g_mutex);
      g_passed.insert(identity(st));
      if (settled) remember_on_disk_locked(identity(st));
    }
    return true;
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

}  // namespace

void vet_in_child(const std::string& path, const std::function<void()>& read_all, const UntrustedLimits& limits) {
  vet_once(path, read_all, limits);
}

// Threads only wait on their children: none of them touches libhdf5 in this process, so a
// fork from one never copies another's half-held library state.
std::size_t vet_all_in_children(const std::vector<std::string>& paths,
                                const std::function<void(const std::string&)>& read_all, int jobs,
                                const UntrustedLimits& limits) {
  if (g_child || paths.empty()) return 0;
  std::atomic<std::size_t> next{0}, ran{0};
  std::vector<std::exception_ptr> failed(paths.size());
  const auto work = [&] {
    for (std::size_t i; (i = next++) < paths.size();) {
      try {
        if (vet_once(paths[i], [&] { read_all(paths[i]); }, limits)) ++ran;
      } catch (...) {
        failed[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> helpers;
  for (int t = 1; t < jobs && std::size_t(t) < paths.size(); ++t) helpers.emplace_back(work);
  work();
  for (auto& h : helpers) h.join();
  for (const auto& f : failed)
    if (f) std::rethrow_exception(f);
  return ran;
}

}  // namespace yelan::camera
