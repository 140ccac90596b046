#include "engine/threads.h"

#include <omp.h>

#include <charconv>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace yelan {

std::optional<int> parse_thread_count(std::string_view text) {
  int n = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, n);
  if (text.empty() || ec != std::errc() || ptr != end || n < 1 || n > 1024) return std::nullopt;
  return n;
}

void set_threads(int n) {
  if (n < 1) throw std::invalid_argument("thread count must be >= 1, got " + std::to_string(n));
  omp_set_num_threads(n);
}

void init_threads_from_env() {
  const char* env = std::getenv("YELAN_THREADS");
  if (!env) return;
  auto n = parse_thread_count(env);
  if (!n)
    throw std::invalid_argument(std::string("YELAN_THREADS='") + env +
                                "' is not a thread count (1..1024)");
  set_threads(*n);
}

int threads() { return omp_get_max_threads(); }

}  // namespace yelan
