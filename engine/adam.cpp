#include "engine/adam.h"

#include <cmath>
#include <stdexcept>

namespace yelan {

Adam::Adam(layers::ParamList params, AdamOptions opt) : o_(opt), lr_(opt.lr) {
  for (auto& p : params)
    if (p.param->trainable) params_.push_back(p);
  for (auto& p : params_) {
    m_.emplace_back(p.param->numel());
    v_.emplace_back(p.param->numel());
  }
}

void Adam::zero_grad() {
  for (auto& p : params_) p.param->grad.zero();
}

double Adam::step() {
  double sq = 0;
  for (auto& p : params_)
    for (std::size_t i = 0; i < p.param->numel(); ++i) sq += double(p.param->grad[i]) * p.param->grad[i];
  const double norm = std::sqrt(sq);
  const double clip = o_.clip_norm > 0 && norm > o_.clip_norm ? o_.clip_norm / (norm + 1e-6) : 1.0;
  ++t_;
  const double bc1 = 1 - std::pow(o_.beta1, double(t_)), bc2 = 1 - std::pow(o_.beta2, double(t_));
  const double step = lr_ / bc1;
  for (std::size_t k = 0; k < params_.size(); ++k) {
    layers::Param& p = *params_[k].param;
    float* m = m_[k].data();
    float* v = v_[k].data();
    for (std::size_t i = 0; i < p.numel(); ++i) {
      const float g = float(p.grad[i] * clip + o_.weight_decay * p.value[i]);
      m[i] = float(o_.beta1 * m[i] + (1 - o_.beta1) * g);
      v[i] = float(o_.beta2 * v[i] + (1 - o_.beta2) * g * g);
      p.value[i] -= float(step * m[i] / (std::sqrt(v[i] / bc2) + o_.eps));
    }
  }
  return norm;
}

void Adam::end_epoch() {
  ++epochs_;
  if (o_.step_size > 0 && epochs_ % o_.step_size == 0) lr_ *= o_.gamma;
}

std::vector<float> Adam::moments() const {
  std::vector<float> out;
  for (const auto& m : m_) out.insert(out.end(), m.data(), m.data() + m.size());
  for (const auto& v : v_) out.insert(out.end(), v.data(), v.data() + v.size());
  return out;
}

void Adam::set_state(const std::vector<float>& moments, std::int64_t t, int epochs, double lr) {
  std::size_t total = 0;
  for (const auto& m : m_) total += m.size();
  if (moments.size() != 2 * total)
    throw std::invalid_argument("adam: saved state has " + std::to_string(moments.size()) + " values, the model needs " +
                                std::to_string(2 * total));
  std::size_t at = 0;
  for (auto& m : m_)
    for (std::size_t i = 0; i < m.size(); ++i) m[i] = moments[at++];
  for (auto& v : v_)
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = moments[at++];
  t_ = t;
  epochs_ = epochs;
  lr_ = lr;
}

}  // namespace yelan
