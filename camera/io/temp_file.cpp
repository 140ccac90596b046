#include "camera/io/temp_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>

namespace yelan::camera {

namespace {

// A fixed table a signal handler can walk. A slot is claimed by one thread, and its path is
// read by the handler only once live (set after the path is complete), so a half-copied path
// is never unlinked.
constexpr int kSlots = 256;
constexpr std::size_t kPathMax = 4096;
std::array<std::atomic<bool>, kSlots> g_claimed{}, g_live{};
std::array<std::array<char, kPathMax>, kSlots> g_paths{};

int register_path(const std::string& p) {
  if (p.size() >= kPathMax) return -1;
  for (std::size_t i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (g_claimed[i].load() || !g_claimed[i].compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_paths[i].data(), p.c_str(), p.size() + 1);
    g_live[i].store(true);
    return int(i);
  }
  return -1;  // more than kSlots at once: still written safely, only not removed on a signal
}

void unregister(int slot) {
  if (slot < 0) return;
  g_live[std::size_t(slot)].store(false);
  g_claimed[std::size_t(slot)].store(false);
}

// A handler on one thread must not remove the files while another thread is between
// registering a name and creating the file (it would create it after the removal, just
// before the process dies). The two sides meet as in Dekker's algorithm: the creator counts
// itself in and then looks for a dying process; the handler marks the process dying and then
// waits for the creators counted in. Sequentially consistent atomics make one of them see
// the other. The creating thread itself, interrupted by the handler, is not waited for.
std::atomic<int> g_creating{0};
std::atomic<bool> g_dying{false};
thread_local bool t_creating = false;

void on_signal(int sig) {
  g_dying.store(true);
  const int self = t_creating ? 1 : 0;
  while (g_creating.load() > self) {
  }
  remove_temp_files();
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// Counts the calling thread in as creating a temporary file; a process already dying by a
// signal waits here for the end instead (the handler is removing the files).
class Creating {
 public:
  Creating() {
    g_creating.fetch_add(1);
    t_creating = true;
    if (g_dying.load()) {
      g_creating.fetch_sub(1);
      t_creating = false;
      for (;;) ::pause();
    }
  }
  ~Creating() {
    t_creating = false;
    g_creating.fetch_sub(1);
  }
};

// A random name the handler may remove even before the file exists: registering first and
// creating second leaves no moment where a signal (delivered to any thread) finds a file of
// ours missing from the registry. A name already taken is never opened (O_EXCL), and a
// signal between registering and finding it taken removes only a name holding our pid.
std::string random_suffix() {
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
  thread_local std::mt19937_64 rng{std::random_device{}() ^ (std::uint64_t(::getpid()) << 32)};
  std::string s(8, 'x');
  for (auto& c : s) c = kAlphabet[rng() % (sizeof kAlphabet - 1)];
  return s;
}

}  // namespace

TempFile::TempFile(std::string final_path) : final_(std::move(final_path)) {
  const std::string stem = final_ + ".tmp-" + std::to_string(long(::getpid())) + "-";
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string name = stem + random_suffix();
    const Creating creating;
    const int slot = register_path(name);
    // open's mode passes through the umask: an output gets what any new file would.
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
    if (fd >= 0) {
      ::close(fd);
      temp_ = std::move(name);
      slot_ = slot;
      return;
    }
    const int err = errno;
    unregister(slot);
    if (err != EEXIST)
      throw std::runtime_error("cannot create a temporary file beside " + final_ + ": " + std::strerror(err));
  }
  throw std::runtime_error("cannot create a temporary file beside " + final_ + ": 100 names taken");
}

TempFile::~TempFile() {
  if (!committed_) ::unlink(temp_.c_str());
  unregister(slot_);
}

void TempFile::commit() {
  if (std::rename(temp_.c_str(), final_.c_str()) != 0)
    throw std::runtime_error("cannot rename " + temp_ + " to " + final_ + ": " + std::strerror(errno));
  committed_ = true;
  unregister(slot_);
  slot_ = -1;
}

void write_file_atomically(const std::string& path, const std::string& text) {
  TempFile tmp(path);
  std::FILE* f = std::fopen(tmp.path().c_str(), "wb");
  const bool ok = f && std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  if (f) std::fclose(f);
  if (!ok) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  tmp.commit();
}

void remove_temp_files() {
  for (int i = 0; i < kSlots; ++i)
    if (g_live[std::size_t(i)].load()) ::unlink(g_paths[std::size_t(i)].data());
}

void remove_temp_files_on_signal() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace yelan::camera
