// 2D convolution (dilation 1, groups 1) on the blocked NCHW16c layout, forward,
// backward-data and backward-weights. The same kernels serve transposed convolution:
// deconv forward is conv backward-data, deconv backward-data is conv forward, and deconv
// backward-weights is conv backward-weights with x and dy swapped.
//
// Layouts (b = 16 everywhere, on every ISA, so a network's activations never change
// layout when the ISA does):
//   activations  [N][ceil(C/16)][H][W][16], lanes past C are zero
//   weights, packed once per weight update by pack_conv_weights():
//     fwd      [OCB][ICB][KH][KW][16 ic][16 oc]
//     bwd_data [ICB][OCB][KH][KW][16 oc][16 ic]
//   weight gradient: the fwd packed layout (unpack_conv_weights() gives OIHW).
//
// Algorithm: direct convolution with register blocking. A tile holds R output pixels of
// one row times NB blocks of 16 output channels in R*NB vector accumulators; every input
// value is broadcast once per tile and every weight vector loaded once per tile, so a
// tile does R*NB FMAs per R+NB loads. Border pixels whose taps leave the image run as
// 1-pixel tiles with only their valid taps, so no input is ever padded or copied.
// The zero lanes that pad the last source block are skipped, not multiplied: a 6-channel
// input (the TORE volume) costs 6/16 of a block, an 8-channel one half.
// Backward-data with stride s splits dx into s x s phases; each phase is a stride-1
// convolution over dy with the taps that land on it.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/cpu.h"

namespace yelan::kernels {

inline constexpr int kBlock = 16;
inline constexpr int kMaxKernel = 11;  // kh, kw up to this

struct ConvShape {
  int n = 1, ic = 1, ih = 1, iw = 1;  // input
  int oc = 1, kh = 1, kw = 1;
  int stride = 1, pad_h = 0, pad_w = 0;
  // fwd and fwd_winograd only: y = max(0, conv + bias), the ReLU of an inference ConvBn fused
  // into the store instead of a pass of its own over y (the other kernels ignore it).
  bool relu = false;
  int oh() const { return (ih + 2 * pad_h - kh) / stride + 1; }
  int ow() const { return (iw + 2 * pad_w - kw) / stride + 1; }
  int icb() const { return (ic + kBlock - 1) / kBlock; }
  int ocb() const { return (oc + kBlock - 1) / kBlock; }
  double flops() const { return 2.0 * n * oh() * ow() * oc * ic * kh * kw; }
  bool valid() const;  // positive sizes, kernel <= kMaxKernel, pad < kernel, output >= 1x1
};

// A convolution input made of two maps side by side in channels, as the U-Net's up path
// concatenates them: a_c channels of `a` (the convolution's input size), then b_c of `b`
// (b_h x b_w, placed at (top, left) with zeros around it: F.pad's). One image (n = 1).
struct ConcatInput {
  const float* a = nullptr;
  int a_c = 0;
  const float* b = nullptr;
  int b_c = 0, b_h = 0, b_w = 0, top = 0, left = 0;
};
// Whether fwd_winograd_cat reads it in place: winograd_applicable(s), n 1, s.ic = a_c + b_c,
// a_c % 8 == 0 (a native vector never takes lanes of both but on 16 lanes, where a block of
// a_c % 16 == 8 joins two halves), no input block past b's (a_c % 16 == 8 with b_c % 16 in 1..8
// is refused), and b inside the input.
bool winograd_cat_applicable(const ConvShape& s, const ConcatInput& in);
// The two as one map of s.ic channels (x_floats of s): what layers::concat_padded makes.
void concat_input(const ConvShape& s, const ConcatInput& in, float* x);

struct ConvKernels {
  Isa isa;
  // y = conv(x, w) + bias (bias may be null; it has ocb()*16 entries, padding zero)
  void (*fwd)(const ConvShape& s, const float* x, const float* w_fwd, const float* bias, float* y);
  // dx = conv_transpose(dy, w) + bias (bias may be null: a backward pass; else a transposed
  // convolution's forward, its bias added in the store; icb()*16 entries, padding zero);
  // overwrites dx
  void (*bwd_data)(const ConvShape& s, const float* dy, const float* w_bwd, const float* bias, float* dx);
  // dw = sum over batch and pixels (fwd packed layout); dbias likewise (may be null).
  // Overwrites both.
  void (*bwd_weights)(const ConvShape& s, const float* x, const float* dy, float* dw, float* dbias);
  // Inference only, 3x3 stride 1 (winograd_applicable): Winograd F(4x4, 3x3) with weights
  // from pack_winograd_weights. Same contract as fwd; error bound in tests/kernels/test_conv.cpp.
  void (*fwd_winograd)(const ConvShape& s, const float* x, const float* w_wino, const float* bias, float* y);
  // fwd_winograd of the concatenation of two maps, read in place by the input transform
  // (winograd_cat_applicable must hold): the same outputs, bit for bit, without the copy.
  void (*fwd_winograd_cat)(const ConvShape& s, const ConcatInput& in, const float* w_wino, const float* bias, float* y);
};

// ConvTranspose2d (PyTorch semantics, weights (in, out, kh, kw)) is the adjoint of the conv
// `as_conv()` whose input is the deconv's output: deconv forward = that conv's
// backward-data, deconv backward-data = its forward, deconv weight gradient = its
// backward-weights with x and dy swapped. PyTorch's (in, out, kh, kw) weights are exactly
// that conv's OIHW, so they pack with pack_conv_weights(as_conv(), ...) unchanged.
struct DeconvShape {
  int n = 1, ic = 1, ih = 1, iw = 1, oc = 1, kh = 1, kw = 1;
  int stride = 1, pad_h = 0, pad_w = 0, out_pad_h = 0, out_pad_w = 0;
  int oh() const { return (ih - 1) * stride - 2 * pad_h + kh + out_pad_h; }
  int ow() const { return (iw - 1) * stride - 2 * pad_w + kw + out_pad_w; }
  int icb() const { return (ic + kBlock - 1) / kBlock; }
  int ocb() const { return (oc + kBlock - 1) / kBlock; }
  ConvShape as_conv() const { return {n, oc, oh(), ow(), ic, kh, kw, stride, pad_h, pad_w}; }
  bool valid() const {
    return out_pad_h >= 0 && out_pad_w >= 0 && out_pad_h < stride && out_pad_w < stride && oh() > 0 &&
           ow() > 0 && as_conv().valid() && as_conv().oh() == ih && as_conv().ow() == iw;
  }
};

const ConvKernels& conv_kernels(Isa isa);
inline const ConvKernels& conv_kernels() { return conv_kernels(active_isa()); }
extern const ConvKernels conv_scalar;  // plain loops: the reference for every variant

enum class ConvPack { fwd, bwd_data };
std::size_t conv_weight_floats(const ConvShape& s);  // either packed layout
void pack_conv_weights(const ConvShape& s, const float* w_oihw, ConvPack pack, float* out);
void unpack_conv_weights(const ConvShape& s, const float* w_fwd, float* w_oihw);

// Winograd F(4x4, 3x3): 4x4 output tiles from 6x6 input tiles, 36 multiplies per tile and
// channel pair instead of 144. Weights are transformed once per weight update (in double)
// into [36][OCB][ICB][16 ic][16 oc]; each of the 36 products is then a GEMM over channels
// run by the same register-blocked tile as the direct convolution.
bool winograd_applicable(const ConvShape& s);
// Whether Winograd beats the direct kernel inside a network, where weights arrive cold: its
// weights are 4x the direct ones (36 products against 9 taps) and each is reused once per
// 4x4 tile, so on maps of a few dozen tiles, or 8-channel blocks half padding, the direct
// kernel wins (stage 2's 8-channel 17x22 convs: 13 against 20 us; 16-channel 9x11: 9 against
// 11 us, one core, cold weights; isolated and hot, Winograd wins both). Wide layers keep it
// whatever their size: on stage 1's 8x10 bottleneck (384 channels) the direct kernel's
// 1-pixel border tiles make it 3x slower.
bool winograd_pays(const ConvShape& s);
// The calling thread's scratch of at least `floats` floats, 64-byte aligned, grown (never
// shrunk) on demand: after the first call of a shape, no allocation. Defined in a baseline
// file so that no container code is instantiated inside an ISA variant.
float* thread_scratch(std::size_t floats);
std::size_t winograd_weight_floats(const ConvShape& s);
// conv_scalar's textbook Winograd with each transformed input passed through round_v before
// its product (the bf16 Winograd's reference rounds there; identity gives conv_scalar's).
void fwd_winograd_scalar_rounded(const ConvShape& s, const float* x, const float* u, const float* bias, float* y,
                                 float (*round_v)(float));
void pack_winograd_weights(const ConvShape& s, const float* w_oihw, float* out);

// Transposed convolution through the conv kernels (see DeconvShape). Weights are packed
// for as_conv(): ConvPack::bwd_data for forward, ConvPack::fwd for backward-data.
void deconv_fwd(const ConvKernels& k, const DeconvShape& s, const float* x, const float* w_bwd, const float* bias,
                float* y);
void deconv_bwd_data(const ConvKernels& k, const DeconvShape& s, const float* dy, const float* w_fwd, float* dx);
// dw in the fwd packed layout of as_conv(); dbias (may be null): per output channel sums.
void deconv_bwd_weights(const ConvKernels& k, const DeconvShape& s, const float* x, const float* dy, float* dw,
                        float* dbias);

}  // namespace yelan::kernels
