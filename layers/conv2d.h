// Conv2d and ConvTranspose2d (PyTorch semantics, dilation 1, groups 1) on the conv
// kernels. Weights live in PyTorch's layout; packed copies for the kernels are rebuilt
// lazily after weights_changed() (a load or an optimizer step), never per call.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "kernels/conv.h"
#include "layers/param.h"

namespace yelan::layers {

struct ConvSpec {
  int in = 1, out = 1, k = 1, stride = 1, pad = 0;
  bool bias = false;
  bool transposed = false;  // ConvTranspose2d: weight (in, out, k, k)
  int out_pad_h = 0, out_pad_w = 0;
};

// Multiply-add FLOPs of every Conv2d forward since the last reset (`conv_flops() = 0`):
// what `yelan model summary` reports. Not thread-safe; a diagnostic.
std::uint64_t& conv_flops();

// Winograd F(4,3) for 3x3/1 forwards where a caller asks for it (inference). Off: the direct
// convolution everywhere, a few ulps closer to a reference. Process-wide.
bool& winograd_allowed();

// Inference convolutions (forward_folded: an eval-mode ConvBn's) of stride 1 and kernel > 1x1
// in bf16 on the CPU's AMX tiles (kernels/conv_bf16.h) where it has them; on a CPU with
// AVX512-BF16 and no AMX, the Winograd ones with their GEMMs in bf16 (the rest stay fp32);
// elsewhere, or off (the default), fp32 as before. Set per thread (the caller's: the kernels' own threads never
// read it); a network sets it for its own forward with Bf16Convs (stage 1 under run.bf16).
bool& bf16_convs();
class Bf16Convs {
 public:
  explicit Bf16Convs(bool on) : saved_(bf16_convs()) { bf16_convs() = on; }
  ~Bf16Convs() { bf16_convs() = saved_; }
  Bf16Convs(const Bf16Convs&) = delete;
  Bf16Convs& operator=(const Bf16Convs&) = delete;

 private:
  bool saved_;
};
// bf16_convs() on a CPU that runs a bf16 path: AMX (kernels::amx_bf16_enabled), or else
// Winograd on AVX512-BF16 (kernels::winograd_bf16_enabled).
bool bf16_active();
enum class Bf16Path { none, amx, winograd };
Bf16Path bf16_path();  // which of them bf16_convs() takes on this CPU now
Bf16Path bf16_path_if(bool on);  // which of them a network with bf16 `on` takes on this CPU
const char* bf16_path_name(Bf16Path p);  // "fp32", "bf16 on AMX", "bf16 Winograd on AVX512-BF16"
// Whether a forward_folded of this shape takes the AMX path now (bf16_path, the shape).
bool takes_bf16(const kernels::ConvShape& s);
// Which bf16 kernel the 2x2/2 up-sampling takes under NoGrad: AMX tiles, the bf16 pairs
// where the path is Winograd on AVX512-BF16 (Bf16Path::winograd), or none (fp32).
Bf16Path up_bf16_path(const kernels::DeconvShape& d);

// One Conv2d forward as `yelan model summary` lists it: which layer (its weight, whose key
// the caller's ParamList knows), the shapes in and out, and the multiply-add FLOPs.
struct ConvRecord {
  const Param* weight;
  int k, stride;
  bool transposed;
  int in_c, in_h, in_w, out_c, out_h, out_w;
  std::uint64_t flops;
};
// When set, every Conv2d forward appends its record here. Not thread-safe; a diagnostic.
std::vector<ConvRecord>*& conv_trace();

class Conv2d {
 public:
  explicit Conv2d(const ConvSpec& spec);

  Param weight;
  std::unique_ptr<Param> bias;

  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);  // PyTorch's default initialisation
  void weights_changed() { packed_ = folded_ = false; }
  const ConvSpec& spec() const { return spec_; }

  // Output geometry for an input (data left null).
  Act out_shape(const Act& x) const;
  // y must have out_shape(x)'s size. Winograd only where applicable (3x3/1) and asked for.
  // A 2x2/2 transposed conv under NoGrad and bf16_convs runs in bf16 (up_bf16_path: AMX tiles,
  // or bf16 pairs on AVX512-BF16).
  void forward(const Act& x, const Act& y, bool winograd = false);
  // Inference through a per-output-channel affine folded into the weights and bias (an
  // eval-mode BatchNorm after this conv): y = scale * conv(x) + shift in one pass. The folded
  // weights are packed on the first call after weights_changed() or fold_changed(). relu: y =
  // max(0, ...) in the same pass (the kernels' store), as a ReLU after the BatchNorm.
  void forward_folded(const Act& x, const Act& y, const float* scale, const float* shift, bool winograd = true,
                      bool relu = false);
  // forward_folded of [a, F.pad(b)] (b at (top, left) of a's size, zeros around it: the
  // U-Net's up path), read in place where the folded forward is a Winograd one
  // (kernels::winograd_cat_applicable) or AMX's (conv_bf16_cat_applicable); false, nothing
  // written, where it is not.
  bool forward_folded_cat(const Act& a, const Act& b, int top, int left, const Act& y, const float* scale,
                          const float* shift, bool relu);
  // forward_folded, then next.forward_folded of its output, as one AMX kernel where both take
  // bf16 on AMX (kernels::conv_pair_fwd_bf16_amx: the output between them stays in bf16 and
  // is not kept); b non-null: this convolution's input is [a, F.pad(b)] read in place. False,
  // nothing written, elsewhere.
  bool forward_folded_pair(const Act& a, const Act* b, int top, int left, const float* scale, const float* shift,
                           bool relu, Conv2d& next, const float* next_scale, const float* next_shift, bool next_relu,
                           const Act& y);
  void fold_changed() { folded_ = false; }
  bool fold_packed() const { return folded_; }  // forward_folded will not read scale and shift
  // Adds dL/dweight (and dL/dbias) to the gradients; writes dx when dx is non-null.
  void backward(const Act& x, const Act& dy, const Act* dx);

 private:
  ConvSpec spec_;
  bool packed_ = false;
  bool folded_ = false;
  Floats fwd_, bwd_, wino_, bias16_, dw_packed_, db16_, dw_plain_;
  Floats fold_w_, fold_wino_, fold_bias16_;
  std::vector<std::uint16_t> fold_bf16_;  // the folded weights for the bf16 kernel, once it is asked for
  std::vector<std::uint16_t> fold_wino_bf16_;  // fold_wino_ in bf16 pairs, once the bf16 Winograd asks
  std::vector<std::uint16_t> up_bf16_;    // a 2x2/2 transposed conv's, packed on its first bf16 forward
  Bf16Path up_bf16_layout_ = Bf16Path::none;  // which kernel's layout up_bf16_ holds
  kernels::ConvShape conv_shape(const Act& x) const;   // the kernel's conv (for a deconv: its adjoint)
  kernels::DeconvShape deconv_shape(const Act& x) const;
  void pack(const kernels::ConvShape& s);
  void check_io(const Act& x, const Act& y) const;
  void record(const Act& x, const Act& y, const kernels::ConvShape& s) const;  // conv_flops, conv_trace
  void pack_folded(const kernels::ConvShape& s, const float* scale, const float* shift);
  enum class FoldedPath { direct, winograd, winograd_bf16, amx };  // direct: run_forward decides
  FoldedPath folded_path(const kernels::ConvShape& s, bool winograd) const;  // after pack_folded
  void pack_winograd_bf16(const kernels::ConvShape& s);
  void pack_amx_bf16(const kernels::ConvShape& s);  // fold_bf16_ from fold_w_, once
  void run_forward(const Act& x, const Act& y, const float* w, const float* wino, const float* bias, bool winograd,
                   bool relu = false);
};

}  // namespace yelan::layers
