// A network's parts, listed once. A network (or a block built the same way) derives from
// Module<Self>, sets kSeedStride and defines ONE visitor over its parts in state_dict order:
//
//   static constexpr std::uint64_t kSeedStride = 1000;
//   template <class F> void for_each_part(F&& f) {
//     f(conv1_, {"in_cnn.0.", 1});   // the part, {its state_dict prefix, its init seed offset}
//     f(bn1_, {"in_cnn.1."});        // no init: no seed
//     ...
//   }
//
// Module derives params(), init(), set_training() and weights_changed() from it, calling on
// each part whichever of them the part has (a BatchNorm2d has no init, a Conv2d no training
// mode, a Linear no packed weights). init(seed) seeds each part kSeedStride * seed + its
// offset, so parts draw independent streams and their order does not matter; params() keeps
// the visitor's order, which weights files and optimizer states follow. A part may itself be
// a Module: its keys nest under its prefix. Parameter-free layers (pooling) are not parts.
// Adding a layer: a member, its construction, one line in for_each_part.
#pragma once
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>

#include "layers/param.h"

namespace yelan::layers {

struct PartKey {
  std::string prefix;       // prepended to the part's own state_dict keys
  std::uint64_t seed = 0;   // init seed offset (parts without init ignore it)
  std::string bn_prefix{};  // a ConvBn's BatchNorm: the reference numbers its conv and BN apart
};

namespace module_detail {
template <class P, class = void>
struct HasInit : std::false_type {};
template <class P>
struct HasInit<P, std::void_t<decltype(std::declval<P&>().init(std::uint64_t()))>> : std::true_type {};
template <class P, class = void>
struct HasSetTraining : std::false_type {};
template <class P>
struct HasSetTraining<P, std::void_t<decltype(std::declval<P&>().set_training(true))>> : std::true_type {};
template <class P, class = void>
struct HasWeightsChanged : std::false_type {};
template <class P>
struct HasWeightsChanged<P, std::void_t<decltype(std::declval<P&>().weights_changed())>> : std::true_type {};
template <class P, class = void>
struct HasTwoKeys : std::false_type {};  // params(conv_key, bn_key, out): ConvBn
template <class P>
struct HasTwoKeys<P, std::void_t<decltype(std::declval<P&>().params(std::string(), std::string(), std::declval<ParamList&>()))>>
    : std::true_type {};
}  // namespace module_detail

template <class Net>
class Module {
 public:
  // Every part's parameters and buffers, keys prefixed, in for_each_part's order.
  void params(const std::string& prefix, ParamList& out) {
    self().for_each_part([&](auto& part, const PartKey& key) {
      if constexpr (module_detail::HasTwoKeys<std::decay_t<decltype(part)>>::value)
        part.params(prefix + key.prefix, prefix + key.bn_prefix, out);
      else
        part.params(prefix + key.prefix, out);
    });
  }
  void params(ParamList& out) { params(std::string(), out); }

  void init(std::uint64_t seed) {
    self().for_each_part([&](auto& part, const PartKey& key) {
      if constexpr (module_detail::HasInit<std::decay_t<decltype(part)>>::value) part.init(seed * Net::kSeedStride + key.seed);
    });
  }

  // Training (batch statistics) or inference (running statistics) for every BatchNorm.
  void set_training(bool on) {
    self().for_each_part([&](auto& part, const PartKey&) {
      if constexpr (module_detail::HasSetTraining<std::decay_t<decltype(part)>>::value) part.set_training(on);
    });
  }

  // After a load or an optimizer step: packed copies of the weights are rebuilt lazily.
  void weights_changed() {
    self().for_each_part([&](auto& part, const PartKey&) {
      if constexpr (module_detail::HasWeightsChanged<std::decay_t<decltype(part)>>::value) part.weights_changed();
    });
  }

 private:
  Net& self() { return static_cast<Net&>(*this); }
};

}  // namespace yelan::layers
