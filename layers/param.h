// Parameters and buffers of a layer: the master copy in PyTorch's layout (so weights files
// map 1:1 to state_dict keys), the gradient beside it, and whether an optimizer updates it.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace yelan::layers {

// Bytes held by every live Floats (parameters, gradients, packed weights, activations),
// and the most held at once since the last reset: the networks' memory, as
// `yelan bench networks` reports it.
std::size_t floats_live_bytes();
std::size_t floats_peak_bytes();
void reset_floats_peak();

// Like torch.no_grad(): inside a NoGrad scope no backward follows a forward, so layers may
// take inference-only shortcuts (an eval-mode BatchNorm folded into the conv before it, no
// buffers kept for the backward). Per thread.
bool grad_enabled();
class NoGrad {
 public:
  NoGrad();
  ~NoGrad();
  NoGrad(const NoGrad&) = delete;
  NoGrad& operator=(const NoGrad&) = delete;

 private:
  bool saved_;
};

// A 64-byte aligned float array (layers may not depend on engine/, so not a Tensor).
class Floats {
 public:
  Floats() = default;
  explicit Floats(std::size_t n);  // zero-filled
  float* data() { return p_.get(); }
  const float* data() const { return p_.get(); }
  std::size_t size() const { return n_; }
  float& operator[](std::size_t i) { return p_.get()[i]; }
  float operator[](std::size_t i) const { return p_.get()[i]; }
  void zero();

 private:
  struct Free {
    std::size_t bytes;  // no default initializer: it would not be usable inside Floats
    void operator()(float* p) const;
  };
  std::unique_ptr<float, Free> p_;
  std::size_t n_ = 0;
};

struct Param {
  std::string name;                 // state_dict key relative to the owning layer
  std::vector<std::int64_t> shape;  // PyTorch shape
  Floats value, grad;
  bool trainable = true;            // false: BN running statistics, num_batches_tracked
  Param(std::string n, std::vector<std::int64_t> s, bool train = true);
  std::size_t numel() const { return value.size(); }
};

// Appends `prefix + p.name` views of a layer's parameters to a model-wide list.
struct NamedParam {
  std::string key;
  Param* param;
};
using ParamList = std::vector<NamedParam>;

// PyTorch's default initialisation of conv/linear layers: U(-1/sqrt(fan_in), 1/sqrt(fan_in))
// for weights and biases (kaiming_uniform with a = sqrt(5) reduces to this bound).
void init_uniform_fan_in(Param& p, std::int64_t fan_in, std::uint64_t seed);

// A blocked NCHW16c activation: n x ceil(c/16) x h x w x 16 floats, padding lanes zero.
struct Act {
  float* data = nullptr;
  int n = 0, c = 0, h = 0, w = 0;
  int cb() const { return (c + 15) / 16; }
  std::size_t pixels() const { return std::size_t(h) * w; }
  std::size_t floats() const { return std::size_t(n) * cb() * pixels() * 16; }
  // Channel ch of pixel px of image img in the blocked layout (img, ch/16, pixel, ch%16): the
  // one place that spells the layout's addressing.
  float* lane(int img, int ch, std::size_t px) const {
    return data + ((std::size_t(img) * cb() + ch / 16) * pixels() + px) * 16 + ch % 16;
  }
};

}  // namespace yelan::layers
