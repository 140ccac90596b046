// Scratch memory for one forward/backward pass. Allocation is a pointer bump; reset()
// releases everything at once. If a pass needed more than the arena held, the excess
// came from extra blocks, and the next reset() regrows the main block to the pass's
// high-water mark, so from the second identical pass on nothing touches malloc.
#pragma once
#include <cstddef>
#include <vector>

#include "engine/aligned.h"

namespace yelan {

class Arena {
 public:
  explicit Arena(std::size_t initial_bytes = 0);
  Arena(const Arena&) = delete;
  Arena& operator=(const Arena&) = delete;

  void* allocate(std::size_t bytes);  // 64-byte aligned; valid until reset()
  float* allocate_floats(std::size_t n) { return static_cast<float*>(allocate(n * sizeof(float))); }
  void reset();

  std::size_t capacity() const { return capacity_; }
  std::size_t used() const { return used_ + overflow_bytes_; }
  std::size_t high_water() const { return high_water_; }
  std::size_t system_allocations() const { return system_allocations_; }

 private:
  AlignedPtr main_;
  std::size_t capacity_ = 0, used_ = 0;
  std::vector<AlignedPtr> overflow_;
  std::size_t overflow_bytes_ = 0;
  std::size_t high_water_ = 0;
  std::size_t system_allocations_ = 0;
};

}  // namespace yelan
