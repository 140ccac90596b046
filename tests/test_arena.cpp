#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>

#include "engine/aligned.h"
#include "engine/arena.h"
#include "engine/tensor.h"

namespace {
bool aligned64(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % 64 == 0; }

// One "pass": a mix of odd-sized activations, as a network's would be.
void pass(yelan::Arena& arena) {
  for (std::size_t bytes : {4u, 100u, 4096u, 33u * 44u * 4u, 1u, 65u * 87u * 64u * 4u}) {
    void* p = arena.allocate(bytes);
    REQUIRE(aligned64(p));
    std::memset(p, 0xAB, bytes);  // ASan flags any overlap or overrun
  }
}
}  // namespace

TEST_CASE("aligned allocations are 64-byte aligned for any size", "[engine][arena]") {
  for (std::size_t bytes : {0u, 1u, 3u, 63u, 64u, 65u, 1000u, 1u << 20}) {
    auto p = yelan::aligned_alloc_bytes(bytes);
    CHECK(aligned64(p.get()));
  }
}

TEST_CASE("an arena stops calling malloc after the first pass", "[engine][arena]") {
  yelan::Arena arena;
  pass(arena);
  const std::size_t first = arena.system_allocations();
  CHECK(first > 0);
  const std::size_t high = arena.high_water();
  arena.reset();
  CHECK(arena.capacity() >= high);
  const std::size_t after_regrow = arena.system_allocations();
  const std::size_t global_before = yelan::aligned_allocation_count();
  for (int i = 0; i < 5; ++i) {
    pass(arena);
    arena.reset();
  }
  CHECK(arena.system_allocations() == after_regrow);
  CHECK(yelan::aligned_allocation_count() == global_before);
  CHECK(arena.high_water() == high);
}

TEST_CASE("arena allocations within a pass do not overlap", "[engine][arena]") {
  yelan::Arena arena(1024);
  char* a = static_cast<char*>(arena.allocate(100));
  char* b = static_cast<char*>(arena.allocate(100));
  char* c = static_cast<char*>(arena.allocate(5000));  // overflows the 1 KiB block
  CHECK((b >= a + 100 || a >= b + 100));
  CHECK((c >= b + 100 || b >= c + 5000));
  CHECK(arena.used() >= 5200);
  arena.reset();
  CHECK(arena.used() == 0);
  CHECK(arena.capacity() >= 5200);
}

TEST_CASE("tensors borrowed from an arena are aligned, sized views", "[engine][arena]") {
  yelan::Arena arena;
  yelan::Tensor t = yelan::Tensor::from_arena(arena, {3, 7, 5});
  CHECK(aligned64(t.data()));
  CHECK_FALSE(t.owns_memory());
  CHECK(t.numel() == 105);
  t.fill(1.f);
  CHECK(t.at({2, 6, 4}) == 1.f);
}
