// Activation storage that a block keeps between its forward and backward: grows to the
// largest shape it has held and never shrinks, so repeated passes allocate nothing.
#pragma once
#include "layers/param.h"

namespace yelan::layers {

class ActBuf {
 public:
  Act get(int n, int c, int h, int w) {
    Act a{nullptr, n, c, h, w};
    if (mem_.size() < a.floats()) mem_ = Floats(a.floats());
    a.data = mem_.data();
    return a;
  }
  Act like(const Act& s) { return get(s.n, s.c, s.h, s.w); }

 private:
  Floats mem_;
};

}  // namespace yelan::layers
