#include "camera/io/temp_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace yelan::camera {

namespace {

// A fixed table a signal handler can walk: a slot is in use while its flag is set.
constexpr int kSlots = 256;
constexpr std::size_t kPathMax = 4096;
std::array<std::atomic<bool>, kSlots> g_used{};
std::array<std::array<char, kPathMax>, kSlots> g_paths{};

int register_path(const std::string& p) {
  if (p.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (g_used[std::size_t(i)].load() || !g_used[std::size_t(i)].compare_exchange_strong(expected, true)) continue;
    std::memcpy(g_paths[std::size_t(i)].data(), p.c_str(), p.size() + 1);
    return i;
  }
  return -1;  // more than kSlots at once: still written safely, only not removed on a signal
}

void unregister(int slot) {
  if (slot >= 0) g_used[std::size_t(slot)].store(false);
}

mode_t file_mode() {
  const mode_t mask = ::umask(0);  // read it (there is no other way) and put it back
  ::umask(mask);
  return 0666 & ~mask;
}

void on_signal(int sig) {
  remove_temp_files();
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

TempFile::TempFile(std::string final_path) : final_(std::move(final_path)) {
  std::string pattern = final_ + ".tmp-" + std::to_string(long(::getpid())) + "-XXXXXX";
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary file beside " + final_ + ": " + std::strerror(errno));
  ::fchmod(fd, file_mode());  // mkstemp makes 0600; an output gets what any new file would
  ::close(fd);
  temp_ = pattern;
  slot_ = register_path(temp_);
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
    if (g_used[std::size_t(i)].load()) ::unlink(g_paths[std::size_t(i)].data());
}

void remove_temp_files_on_signal() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

}  // namespace yelan::camera
