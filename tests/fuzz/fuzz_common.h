// Shared by the libFuzzer targets: readers take file paths, so each input is written to a
// per-process scratch file and read to the end. A FormatError is the expected outcome of
// bad bytes; any other exception, a crash, a sanitizer report or a hang is a finding.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <algorithm>
#include <climits>
#include <cstdio>
#include <string>
#include <vector>

#include "camera/io/event_reader.h"

namespace yelan::fuzz {

inline const std::string& scratch_path(const char* ext) {
  static const std::string path = "/tmp/yelan_fuzz_" + std::to_string(::getpid()) + ext;
  return path;
}

inline void write_input(const std::string& path, const std::uint8_t* data, std::size_t size,
                        const std::string& prefix = "") {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) __builtin_trap();
  if (!prefix.empty()) std::fwrite(prefix.data(), 1, prefix.size(), f);
  if (size) std::fwrite(data, 1, size, f);
  std::fclose(f);
}

// Reads everything, both by count and by time window, and checks the reader's promises.
inline void drain(camera::EventReader& r) {
  std::vector<camera::Event> batch;
  std::uint64_t n = 0;
  std::int64_t t_lo = INT64_MAX, t_hi = INT64_MIN;
  while (true) {
    batch.clear();
    const std::size_t got = r.read(batch, 1000);
    if (got == 0) break;
    if (got != batch.size() || got > 1000) __builtin_trap();
    for (const camera::Event& e : batch) t_lo = std::min(t_lo, e.t), t_hi = std::max(t_hi, e.t);
    for (const camera::Event& e : batch)
      if ((r.info().width > 0 && e.x >= r.info().width) || (r.info().height > 0 && e.y >= r.info().height))
        __builtin_trap();  // out-of-range events must have been dropped
    n += got;
  }
  r.rewind();
  std::uint64_t again = 0;
  constexpr std::int64_t kMax = INT64_MAX;
  while (auto next = r.peek_time()) {
    batch.clear();
    if (*next > kMax - 50'000) again += r.read(batch, 5000);  // no window end above it
    else again += r.read_until(batch, *next + 50'000, 5000);
  }
  if (again != n) __builtin_trap();  // both ways of reading see the same events
  // Seeking (through an index the file provides, e.g. AEDAT 4.0's data table) must not crash
  // and can only land on events the stream holds.
  if (n > 0) {
    r.seek(t_lo / 2 + t_hi / 2);
    std::uint64_t after = 0;
    batch.clear();
    while (r.read(batch, 1000) > 0) {
      after += batch.size();
      batch.clear();
    }
    if (after > n) __builtin_trap();
  }
}

template <typename Open>
int run_one(const std::uint8_t* data, std::size_t size, const char* ext, Open open, const std::string& prefix = "") {
  const std::string& path = scratch_path(ext);
  write_input(path, data, size, prefix);
  try {
    auto r = open(path);
    drain(*r);
  } catch (const camera::FormatError&) {
  }
  return 0;
}

}  // namespace yelan::fuzz
