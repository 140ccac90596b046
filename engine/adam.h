// Adam with L2 weight decay as PyTorch's torch.optim.Adam (decay added to the gradient
// before the moments, bias-corrected steps), a step LR schedule (multiply by gamma every
// step_size epochs), and optional clipping of the global gradient norm. State (moments,
// step count, lr) is saved and restored with the model's checkpoints.
#pragma once
#include <cstdint>
#include <vector>

#include "layers/param.h"

namespace yelan {

struct AdamOptions {
  double lr = 1e-3, beta1 = 0.9, beta2 = 0.999, eps = 1e-8, weight_decay = 1e-5;
  double clip_norm = 0;  // 0: no clipping
  int step_size = 10;    // epochs per LR step
  double gamma = 0.5;
};

class Adam {
 public:
  Adam(layers::ParamList params, AdamOptions opt);
  // One update from the accumulated gradients; returns the gradient norm before clipping.
  double step();
  void zero_grad();
  void end_epoch();  // advances the LR schedule
  void set_lr(double lr) { lr_ = lr; }  // a schedule computed by the caller (by steps)
  double lr() const { return lr_; }
  std::int64_t steps() const { return t_; }
  int epochs() const { return epochs_; }
  // Flat state for checkpoints: [m..., v...] over trainable params in order.
  std::vector<float> moments() const;
  void set_state(const std::vector<float>& moments, std::int64_t t, int epochs, double lr);

 private:
  layers::ParamList params_;
  AdamOptions o_;
  std::vector<layers::Floats> m_, v_;
  std::int64_t t_ = 0;
  int epochs_ = 0;
  double lr_;
};

}  // namespace yelan
