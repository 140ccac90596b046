// The one storage for activations (block outputs kept between forward and backward, the
// trainer's batches, the pipeline's frames); scratch inside a kernel call comes from
// kernels::thread_scratch. A buffer grows to the largest shape it has held and never
// shrinks, so repeated passes allocate nothing. Memory starts zeroed when it grows and is
// otherwise reused as it is: a user that changes shapes writes every value it reads.
#pragma once
#include "layers/param.h"

namespace yelan::layers {

class ActBuf {
 public:
  Act act;  // the shape last asked for, over this buffer's memory

  Act get(int n, int c, int h, int w) {
    const Act a{nullptr, n, c, h, w};
    if (mem_.size() < a.floats()) mem_ = Floats(a.floats());
    act = a;
    act.data = mem_.data();
    return act;
  }
  Act like(const Act& s) { return get(s.n, s.c, s.h, s.w); }
  void resize(int n, int c, int h, int w) { get(n, c, h, w); }

 private:
  Floats mem_;
};

}  // namespace yelan::layers
