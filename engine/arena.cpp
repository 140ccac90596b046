#include "engine/arena.h"

#include <algorithm>

namespace yelan {

Arena::Arena(std::size_t initial_bytes) {
  if (initial_bytes > 0) {
    capacity_ = round_up(initial_bytes, kAlignment);
    main_ = aligned_alloc_bytes(capacity_);
    ++system_allocations_;
  }
}

void* Arena::allocate(std::size_t bytes) {
  const std::size_t size = round_up(bytes == 0 ? 1 : bytes, kAlignment);
  void* p;
  if (used_ + size <= capacity_) {
    p = static_cast<char*>(main_.get()) + used_;
    used_ += size;
  } else {
    overflow_.push_back(aligned_alloc_bytes(size));
    ++system_allocations_;
    overflow_bytes_ += size;
    p = overflow_.back().get();
  }
  high_water_ = std::max(high_water_, used_ + overflow_bytes_);
  return p;
}

void Arena::reset() {
  if (!overflow_.empty()) {
    overflow_.clear();
    main_.reset();
    capacity_ = round_up(high_water_, kAlignment);
    main_ = aligned_alloc_bytes(capacity_);
    ++system_allocations_;
  }
  used_ = 0;
  overflow_bytes_ = 0;
}

}  // namespace yelan
