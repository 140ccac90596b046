#include "engine/aligned.h"

#include <atomic>
#include <cstdlib>
#include <new>

namespace yelan {
namespace {
std::atomic<std::size_t> g_allocations{0};
}

void AlignedFree::operator()(void* p) const noexcept { std::free(p); }

AlignedPtr aligned_alloc_bytes(std::size_t bytes) {
  void* p = std::aligned_alloc(kAlignment, round_up(bytes == 0 ? 1 : bytes, kAlignment));
  if (!p) throw std::bad_alloc();
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return AlignedPtr(p);
}

std::size_t aligned_allocation_count() { return g_allocations.load(std::memory_order_relaxed); }

}  // namespace yelan
