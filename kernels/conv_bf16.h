// Inference convolution in bf16 on AMX tiles (Intel Sapphire Rapids and later): stride 1,
// any kernel and padding, NCHW16c fp32 in and out like the other conv kernels. Inputs and
// weights are rounded to bf16 (round to nearest even, subnormals to zero); their products
// are exact in fp32 and summed in fp32, so the result is the convolution of the rounded
// operands up to fp32 summation (bound in tests/kernels/test_conv_bf16.cpp).
//
// Why direct and not Winograd: one TDPBF16PS is 16x16x32 multiply-adds, 16 times the FMA
// units' rate, so the four-fold saving of Winograd no longer pays for its transforms (which
// were a fifth of stage 1 in fp32), and Winograd's large intermediate values would lose
// more to bf16's 8-bit mantissa than the direct sum does.
//
// Algorithm: the input is copied once per call into bf16 with its zero padding, as
// [ICP][rows][32] (ICP = pairs of 16-channel blocks: one 64-byte tile row is 32 channels of
// one pixel, in channel order). On that padded plane of width Wp the output pixel (oh, ow)
// is row oh*Wp+ow and tap (i, j) reads the input row oh*Wp+ow + i*Wp+j, so 16 consecutive
// output rows are 16 consecutive input rows for every tap: one tile load, no gather. The
// Wp-OW rows per line that fall in the padding are computed and dropped. A task is 32
// output rows x 32 channels in four fp32 accumulator tiles; weights are packed once as
// [OCB][ICP][KH][KW] tiles of 16 channel pairs x 16 outputs x 2 (the pairs TDPBF16PS reads).
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/conv.h"

namespace yelan::kernels {

// Pairs of 16-channel input blocks: one 64-byte tile row is 32 channels of one pixel.
inline int bf16_pairs(int icb) { return (icb + 1) / 2; }
// Where input channel k (of its pair) and output channel n (of its block) sit in a 16 x 32
// weight tile: row k/2 holds channels k and k+1 of all 16 outputs, interleaved.
inline int bf16_tile_index(int k, int n) { return (k / 2) * 32 + n * 2 + k % 2; }

// The CPU has AMX-TILE and AMX-BF16, the OS saves tile state, and this process was granted
// it (Linux arch_prctl ARCH_REQ_XCOMP_PERM, asked once). False on every other build.
bool amx_bf16_available();
bool conv_bf16_applicable(const ConvShape& s);  // stride 1 (and valid)

std::size_t conv_bf16_weight_halves(const ConvShape& s);
void pack_conv_bf16_weights(const ConvShape& s, const float* w_oihw, std::uint16_t* out);
// Same contract as ConvKernels::fwd (bias may be null, s.relu fused). amx_bf16_available()
// must hold; throws std::logic_error otherwise.
void conv_fwd_bf16_amx(const ConvShape& s, const float* x, const std::uint16_t* w_bf16, const float* bias, float* y);
// The same of two maps concatenated in channels, read in place: the copy into bf16 that the
// tiles read is made straight from a and b (where a_c % 16 == 8 a block of each meets in one
// vector), bit for bit the result on their copy (concat_input). Holds where conv_bf16 does
// for one image of a_c + b_c channels, a_c a multiple of 8 and b inside the input.
bool conv_bf16_cat_applicable(const ConvShape& s, const ConcatInput& in);
void conv_fwd_bf16_amx_cat(const ConvShape& s, const ConcatInput& in, const std::uint16_t* w_bf16, const float* bias,
                           float* y);
// Two stride-1 convolutions in a row (the U-Net's double convolution): the first's outputs,
// its bias and ReLU applied, are stored straight into the bf16 plane the second reads, never
// to memory in fp32 and back (a full-resolution map of 24 channels is 2.9 MB in fp32). Bit for
// bit the two conv_fwd_bf16_amx calls: the same sums, rounded to bf16 once, where the second
// call would have rounded them. in.b null: one map in.a of s1.ic channels; else the two maps
// read in place (conv_bf16_cat_applicable). s2 takes s1's output (conv_bf16_pair_applicable).
bool conv_bf16_pair_applicable(const ConvShape& s1, const ConvShape& s2);
void conv_pair_fwd_bf16_amx(const ConvShape& s1, const ConcatInput& in, const std::uint16_t* w1, const float* bias1,
                            const ConvShape& s2, const std::uint16_t* w2, const float* bias2, float* y);

// The U-Net's up-sampling, a 2x2 stride-2 transposed convolution (no padding): per output
// phase (dy, dx) a 1x1 convolution of the input, so one GEMM over the input's pixels with
// four times the output channels, each accumulator row stored at (2h + dy, 2w + dx).
// Weights are PyTorch's (in, out, 2, 2), packed as [4 phases x OCB][ICP] tiles.
bool deconv2x2_bf16_applicable(const DeconvShape& d);
std::size_t deconv2x2_bf16_weight_halves(const DeconvShape& d);
void pack_deconv2x2_bf16_weights(const DeconvShape& d, const float* w_iohw, std::uint16_t* out);
void deconv2x2_fwd_bf16_amx(const DeconvShape& d, const float* x, const std::uint16_t* w_bf16, const float* bias,
                            float* y);

// What conv_bf16_amx.cpp exports: its kernels behind a table, as the ISA variant files do.
struct AmxBf16Kernels {
  void (*conv)(const ConvShape& s, const float* x, const std::uint16_t* w, const float* bias, float* y);
  void (*conv_cat)(const ConvShape& s, const ConcatInput& in, const std::uint16_t* w, const float* bias, float* y);
  void (*conv_pair)(const ConvShape& s1, const ConcatInput& in, const std::uint16_t* w1, const float* bias1,
                    const ConvShape& s2, const std::uint16_t* w2, const float* bias2, float* y);
  void (*deconv2x2)(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y);
};

// Whether the bf16 path is to run now: amx_bf16_available() and no narrower ISA forced
// (YELAN_ISA, --isa: a run pinned to avx2 or scalar stays off AVX-512 and AMX).
bool amx_bf16_enabled();

// Winograd F(4x4, 3x3) with its GEMMs in bf16, for CPUs with AVX512-BF16 and no AMX (AMD Zen
// 4 and 5). VDPBF16PS does two multiply-adds a lane where VFMADD231PS does one, and on Zen 5
// issues at its rate over 24 chains: 2x the fp32 GEMMs, which are 57% of stage 1 in fp32. The
// transforms stay fp32; each transformed input is rounded to bf16 once (the input transform's
// store), the transformed weights once when packed (from pack_winograd_weights' fp32, made
// in double). Winograd's transformed values run larger than the inputs, but rounding is
// relative: the error bound is in tests/kernels/test_conv_bf16.cpp, and on stage 1 the 56
// validation dancers' mask IoU was the fp32 one to the printed digit (models/README.md).
// Weights: [36][OCB][ICB][8 pairs][16 oc][2] halves (bf16_tile_index within each block).
bool winograd_bf16_available();  // built with AVX512-BF16, and the CPU and OS give AVX-512 and it
bool winograd_bf16_enabled();    // available, and no narrower ISA forced (as amx_bf16_enabled)
// Where a layer takes it: winograd_pays, and also few input channels into 16 or more outputs
// (stage 1's first convolution, 6 -> 24): one input block's transform, the GEMMs a pair a
// lane, against the direct fp32 kernel's 9 x ic FMAs a pixel and block.
bool winograd_bf16_pays(const ConvShape& s);
std::size_t winograd_bf16_weight_halves(const ConvShape& s);
// From pack_winograd_weights' output (the fp32 transformed weights).
void pack_winograd_bf16_weights(const ConvShape& s, const float* u_wino, std::uint16_t* out);
// Same contract as ConvKernels::fwd_winograd; winograd_bf16_available() must hold (throws
// std::logic_error otherwise), and winograd_applicable(s).
void conv_fwd_winograd_bf16(const ConvShape& s, const float* x, const std::uint16_t* u_bf16, const float* bias,
                            float* y);
// conv_fwd_winograd_bf16 of two maps concatenated in channels, read in place
// (winograd_cat_applicable must hold, as ConvKernels::fwd_winograd_cat): the same outputs.
void conv_fwd_winograd_bf16_cat(const ConvShape& s, const ConcatInput& in, const std::uint16_t* u_bf16,
                                const float* bias, float* y);
// The U-Net's up-sampling in the same bf16 pairs (deconv2x2_bf16_applicable shapes): four
// GEMMs over the input's pixels, one per output phase, where there is no AMX. Weights are
// PyTorch's (in, out, 2, 2), packed as [4 phases][OCB][ICB][8 pairs][16 oc][2] halves; the
// reference is deconv2x2_fwd_bf16_reference. winograd_bf16_available() must hold.
std::size_t deconv2x2_bf16_pairs_weight_halves(const DeconvShape& d);
void pack_deconv2x2_bf16_pairs_weights(const DeconvShape& d, const float* w_iohw, std::uint16_t* out);
void deconv2x2_fwd_bf16_pairs(const DeconvShape& d, const float* x, const std::uint16_t* w_bf16, const float* bias,
                              float* y);
struct WinogradBf16Kernels {
  void (*fwd)(const ConvShape& s, const float* x, const std::uint16_t* u, const float* bias, float* y);
  void (*fwd_cat)(const ConvShape& s, const ConcatInput& in, const std::uint16_t* u, const float* bias, float* y);
  void (*deconv2x2)(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y);
};

// bf16 as AMX reads it: round to nearest even, subnormals to signed zero, NaN kept NaN.
std::uint16_t to_bf16(float v);
float from_bf16(std::uint16_t h);
// The references: the scalar kernels (conv_scalar) on the bf16-rounded x and w.
void conv_fwd_bf16_reference(const ConvShape& s, const float* x, const float* w_oihw, const float* bias, float* y);
// The scalar Winograd with the transformed weights and each transformed input rounded to bf16.
void conv_fwd_winograd_bf16_reference(const ConvShape& s, const float* x, const float* w_oihw, const float* bias,
                                      float* y);
void deconv2x2_fwd_bf16_reference(const DeconvShape& d, const float* x, const float* w_iohw, const float* bias, float* y);

}  // namespace yelan::kernels
