// The ConvLSTM cell's point-wise update, after the gate convolution conv(cat[x, h]).
// Gate pre-activations come as 4 groups of `hb` channel blocks, in PyTorch's split order
// i, f, o, g (the layer pads each gate group to whole blocks when packing the weights):
//   i, f, o = sigmoid(.), g = tanh(.), c = f * c_prev + i * g, h = o * tanh(c).
// Shapes: gates/act [N][4 hb][pixels][16]; c_prev, c, h, tanh_c [N][hb][pixels][16].
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct LstmShape {
  int n = 1, hb = 1;
  std::size_t pixels = 1;
};

struct LstmKernels {
  Isa isa;
  // act and tanh_c are saved for the backward pass. c_prev may be null (zero state).
  void (*fwd)(const LstmShape& s, const float* gates, const float* c_prev, float* act, float* c, float* h,
              float* tanh_c);
  // dh: gradient of h; dc: gradient of c from step t+1 (null = none). Writes the gradient of
  // the gate pre-activations and of c_prev (dc_prev may be null).
  void (*bwd)(const LstmShape& s, const float* act, const float* c_prev, const float* tanh_c, const float* dh,
              const float* dc, float* dgates, float* dc_prev);
};

const LstmKernels& lstm_kernels(Isa isa);
inline const LstmKernels& lstm_kernels() { return lstm_kernels(active_isa()); }
extern const LstmKernels lstm_scalar;

}  // namespace yelan::kernels
