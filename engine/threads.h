// How many OpenMP threads the engine's parallel regions use.
#pragma once
#include <optional>
#include <string_view>

namespace yelan {

// "1".."1024"; anything else (empty, 0, negative, junk, trailing text) is nullopt.
std::optional<int> parse_thread_count(std::string_view text);
// Applies YELAN_THREADS if it is set. Throws std::invalid_argument on a bad value.
void init_threads_from_env();
void set_threads(int n);  // throws std::invalid_argument unless n >= 1
int threads();            // what the next parallel region will use

}  // namespace yelan
