// 64-byte aligned heap memory: a cache line, and one AVX-512 register.
#pragma once
#include <cstddef>
#include <memory>

namespace yelan {

inline constexpr std::size_t kAlignment = 64;

struct AlignedFree {
  void operator()(void* p) const noexcept;
};
using AlignedPtr = std::unique_ptr<void, AlignedFree>;

// Throws std::bad_alloc on failure; size 0 gives a valid, unique, aligned pointer.
AlignedPtr aligned_alloc_bytes(std::size_t bytes);
// Process-wide count of aligned_alloc_bytes calls (lets tests prove a pass allocates nothing).
std::size_t aligned_allocation_count();

inline std::size_t round_up(std::size_t n, std::size_t to) { return (n + to - 1) / to * to; }

}  // namespace yelan
