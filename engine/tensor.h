// float32 tensors: owning (64-byte aligned, shared between views) or borrowed (arena,
// caller memory). A tensor is a shape, strides in elements, and a layout tag.
//
// Layouts. `plain`: any rank, any strides (rank 4 reads as NCHW). Blocked `nchw{16,8,4}c`:
// logical (N, C, H, W) stored physically as (N, ceil(C/b), H, W, b), so the b channels of
// one pixel sit in one SIMD register; lanes past C are padding and kept at zero.
#pragma once
#include <array>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>

namespace yelan {

class Arena;

enum class Layout : std::uint8_t { plain, nchw16c, nchw8c, nchw4c };
int block_size(Layout layout);  // 1 for plain
const char* layout_name(Layout layout);

inline constexpr int kMaxRank = 6;

class Dims {
 public:
  Dims() = default;
  Dims(std::initializer_list<std::int64_t> d);
  int rank() const { return rank_; }
  std::int64_t operator[](int i) const { return d_[i]; }
  std::int64_t& operator[](int i) { return d_[i]; }
  std::int64_t product() const;
  void push_back(std::int64_t v);
  bool operator==(const Dims& o) const;
  std::string str() const;  // "[2, 3, 4]"
 private:
  std::array<std::int64_t, kMaxRank> d_{};
  int rank_ = 0;
};

class Tensor {
 public:
  Tensor() = default;

  static Tensor empty(const Dims& shape);  // owning, contiguous, uninitialised
  static Tensor zeros(const Dims& shape);
  // Logical (n, c, h, w) in a blocked layout; padding lanes are zeroed.
  static Tensor empty_blocked(std::int64_t n, std::int64_t c, std::int64_t h, std::int64_t w,
                              Layout layout);
  // Non-owning: the memory must outlive every view of it.
  static Tensor borrow(float* data, const Dims& shape);
  static Tensor from_arena(Arena& arena, const Dims& shape);

  bool defined() const { return data_ != nullptr; }
  int rank() const { return shape_.rank(); }
  const Dims& shape() const { return shape_; }
  const Dims& strides() const { return strides_; }
  std::int64_t size(int dim) const;
  std::int64_t stride(int dim) const;
  std::int64_t numel() const { return shape_.product(); }
  Layout layout() const { return layout_; }
  // Logical channels of a blocked tensor (physical dims 1 and 4 hold ceil(C/b) x b).
  std::int64_t channels() const { return channels_; }
  float* data() const { return data_; }
  bool owns_memory() const { return storage_ != nullptr; }
  long use_count() const { return storage_.use_count(); }

  bool is_contiguous() const;
  // Element access by physical index; bounds are checked and throw std::out_of_range.
  float& at(std::initializer_list<std::int64_t> index) const;
  // A logical (n, c, h, w) element, whatever the layout (rank-4 plain or blocked).
  float& at_nchw(std::int64_t n, std::int64_t c, std::int64_t h, std::int64_t w) const;

  // Views share memory with this tensor.
  Tensor slice(int dim, std::int64_t begin, std::int64_t end) const;
  Tensor select(int dim, std::int64_t index) const;  // drops `dim`
  Tensor reshape(const Dims& shape) const;           // contiguous tensors only
  Tensor clone() const;                              // contiguous owning copy, same layout
  void fill(float value) const;
  void copy_from(const Tensor& src) const;           // same shape, any strides

 private:
  std::shared_ptr<void> storage_;
  float* data_ = nullptr;
  Dims shape_, strides_;
  Layout layout_ = Layout::plain;
  std::int64_t channels_ = 0;
  void set_contiguous_strides();
};

// Conversions at the network's edges (inside it, activations stay blocked).
Tensor to_blocked(const Tensor& nchw, Layout layout);
Tensor to_nchw(const Tensor& blocked);

}  // namespace yelan
