#include "engine/tensor.h"

#include <cstring>
#include <stdexcept>

#include "engine/aligned.h"
#include "engine/arena.h"

namespace yelan {
namespace {

[[noreturn]] void fail_range(const std::string& what) { throw std::out_of_range(what); }

std::int64_t checked_product(const Dims& d) {
  std::int64_t p = 1;
  for (int i = 0; i < d.rank(); ++i) {
    if (d[i] < 0) throw std::invalid_argument("negative dimension in shape " + d.str());
    if (d[i] != 0 && p > (std::int64_t(1) << 40) / d[i])
      throw std::invalid_argument("shape " + d.str() + " is too large");
    p *= d[i];
  }
  return p;
}

// Visits every element of `t` (any strides) in row-major logical order.
template <class F>
void for_each_offset(const Tensor& t, F&& f) {
  const int r = t.rank();
  if (t.numel() == 0) return;
  std::array<std::int64_t, kMaxRank> idx{};
  std::int64_t off = 0;
  for (std::int64_t k = 0, n = t.numel(); k < n; ++k) {
    f(off);
    for (int d = r - 1; d >= 0; --d) {
      if (++idx[d] < t.size(d)) { off += t.stride(d); break; }
      off -= (t.size(d) - 1) * t.stride(d);
      idx[d] = 0;
    }
  }
}

}  // namespace

int block_size(Layout layout) {
  switch (layout) {
    case Layout::plain: return 1;
    case Layout::nchw16c: return 16;
    case Layout::nchw8c: return 8;
    case Layout::nchw4c: return 4;
  }
  return 1;
}

const char* layout_name(Layout layout) {
  switch (layout) {
    case Layout::plain: return "plain";
    case Layout::nchw16c: return "nchw16c";
    case Layout::nchw8c: return "nchw8c";
    case Layout::nchw4c: return "nchw4c";
  }
  return "?";
}

Dims::Dims(std::initializer_list<std::int64_t> d) {
  if (d.size() > kMaxRank) throw std::invalid_argument("rank above " + std::to_string(kMaxRank));
  for (auto v : d) d_[rank_++] = v;
}
std::int64_t Dims::product() const {
  std::int64_t p = 1;
  for (int i = 0; i < rank_; ++i) p *= d_[i];
  return p;
}
void Dims::push_back(std::int64_t v) {
  if (rank_ == kMaxRank) throw std::invalid_argument("rank above " + std::to_string(kMaxRank));
  d_[rank_++] = v;
}
bool Dims::operator==(const Dims& o) const {
  if (rank_ != o.rank_) return false;
  for (int i = 0; i < rank_; ++i)
    if (d_[i] != o.d_[i]) return false;
  return true;
}
std::string Dims::str() const {
  std::string s = "[";
  for (int i = 0; i < rank_; ++i) s += (i ? ", " : "") + std::to_string(d_[i]);
  return s + "]";
}

void Tensor::set_contiguous_strides() {
  strides_ = shape_;
  std::int64_t s = 1;
  for (int i = shape_.rank() - 1; i >= 0; --i) {
    strides_[i] = s;
    s *= shape_[i];
  }
}

Tensor Tensor::empty(const Dims& shape) {
  Tensor t;
  const std::int64_t n = checked_product(shape);
  AlignedPtr mem = aligned_alloc_bytes(static_cast<std::size_t>(n) * sizeof(float));
  t.data_ = static_cast<float*>(mem.get());
  t.storage_ = std::shared_ptr<void>(mem.release(), AlignedFree{});
  t.shape_ = shape;
  t.set_contiguous_strides();
  return t;
}

Tensor Tensor::zeros(const Dims& shape) {
  Tensor t = empty(shape);
  std::memset(t.data_, 0, static_cast<std::size_t>(t.numel()) * sizeof(float));
  return t;
}

Tensor Tensor::empty_blocked(std::int64_t n, std::int64_t c, std::int64_t h, std::int64_t w,
                             Layout layout) {
  if (layout == Layout::plain) throw std::invalid_argument("empty_blocked needs a blocked layout");
  const std::int64_t b = block_size(layout);
  Tensor t = zeros({n, (c + b - 1) / b, h, w, b});
  t.layout_ = layout;
  t.channels_ = c;
  return t;
}

Tensor Tensor::borrow(float* data, const Dims& shape) {
  if (!data && checked_product(shape) > 0) throw std::invalid_argument("borrow of a null pointer");
  Tensor t;
  t.data_ = data;
  t.shape_ = shape;
  t.set_contiguous_strides();
  return t;
}

Tensor Tensor::from_arena(Arena& arena, const Dims& shape) {
  const std::int64_t n = checked_product(shape);
  return borrow(arena.allocate_floats(static_cast<std::size_t>(n)), shape);
}

std::int64_t Tensor::size(int dim) const {
  if (dim < 0 || dim >= rank()) fail_range("dim " + std::to_string(dim) + " of rank " + std::to_string(rank()));
  return shape_[dim];
}
std::int64_t Tensor::stride(int dim) const {
  if (dim < 0 || dim >= rank()) fail_range("dim " + std::to_string(dim) + " of rank " + std::to_string(rank()));
  return strides_[dim];
}

bool Tensor::is_contiguous() const {
  std::int64_t s = 1;
  for (int i = rank() - 1; i >= 0; --i) {
    if (shape_[i] != 1 && strides_[i] != s) return false;
    s *= shape_[i];
  }
  return true;
}

float& Tensor::at(std::initializer_list<std::int64_t> index) const {
  if (static_cast<int>(index.size()) != rank())
    fail_range(std::to_string(index.size()) + " indices for a rank-" + std::to_string(rank()) + " tensor");
  std::int64_t off = 0;
  int d = 0;
  for (auto i : index) {
    if (i < 0 || i >= shape_[d])
      fail_range("index " + std::to_string(i) + " out of range for dim " + std::to_string(d) +
                 " of " + shape_.str());
    off += i * strides_[d++];
  }
  return data_[off];
}

float& Tensor::at_nchw(std::int64_t n, std::int64_t c, std::int64_t h, std::int64_t w) const {
  if (layout_ == Layout::plain) return at({n, c, h, w});
  if (c < 0 || c >= channels_) fail_range("channel " + std::to_string(c) + " of " + std::to_string(channels_));
  const std::int64_t b = block_size(layout_);
  return at({n, c / b, h, w, c % b});
}

Tensor Tensor::slice(int dim, std::int64_t begin, std::int64_t end) const {
  const std::int64_t n = size(dim);
  if (begin < 0 || end > n || begin > end)
    fail_range("slice [" + std::to_string(begin) + ", " + std::to_string(end) + ") of dim " +
               std::to_string(dim) + " with size " + std::to_string(n));
  Tensor t = *this;
  t.data_ = data_ + begin * strides_[dim];
  t.shape_[dim] = end - begin;
  if (layout_ != Layout::plain && dim == 1) {
    const std::int64_t b = block_size(layout_);
    t.channels_ = std::min(channels_ - begin * b, (end - begin) * b);
  }
  return t;
}

Tensor Tensor::select(int dim, std::int64_t index) const {
  Tensor s = slice(dim, index, index + 1);
  Tensor t;
  t.storage_ = s.storage_;
  t.data_ = s.data_;
  for (int i = 0; i < rank(); ++i)
    if (i != dim) {
      t.shape_.push_back(s.shape_[i]);
      t.strides_.push_back(s.strides_[i]);
    }
  return t;  // a blocked tensor loses its layout tag once a dimension is gone
}

Tensor Tensor::reshape(const Dims& shape) const {
  if (!is_contiguous()) throw std::invalid_argument("reshape of a non-contiguous view " + shape_.str());
  if (checked_product(shape) != numel())
    throw std::invalid_argument("reshape " + shape_.str() + " -> " + shape.str() + " changes the element count");
  Tensor t = *this;
  t.shape_ = shape;
  t.set_contiguous_strides();
  t.layout_ = Layout::plain;
  t.channels_ = 0;
  return t;
}

Tensor Tensor::clone() const {
  Tensor t = empty(shape_);
  t.copy_from(*this);
  t.layout_ = layout_;
  t.channels_ = channels_;
  return t;
}

void Tensor::fill(float value) const {
  for_each_offset(*this, [&](std::int64_t off) { data_[off] = value; });
}

void Tensor::copy_from(const Tensor& src) const {
  if (!(src.shape_ == shape_))
    throw std::invalid_argument("copy_from " + src.shape_.str() + " into " + shape_.str());
  if (is_contiguous() && src.is_contiguous()) {
    std::memmove(data_, src.data_, static_cast<std::size_t>(numel()) * sizeof(float));
    return;
  }
  float* dst = data_;
  const float* from = src.data_;
  // Two walks in lockstep: both visit logical order, so the k-th offsets correspond.
  std::int64_t k = 0;
  Tensor flat = empty({numel()});
  for_each_offset(src, [&](std::int64_t off) { flat.data_[k++] = from[off]; });
  k = 0;
  for_each_offset(*this, [&](std::int64_t off) { dst[off] = flat.data_[k++]; });
}

Tensor to_blocked(const Tensor& x, Layout layout) {
  if (x.rank() != 4 || x.layout() != Layout::plain)
    throw std::invalid_argument("to_blocked expects a plain rank-4 NCHW tensor, got " + x.shape().str());
  const std::int64_t N = x.size(0), C = x.size(1), H = x.size(2), W = x.size(3);
  Tensor y = Tensor::empty_blocked(N, C, H, W, layout);
  const std::int64_t b = block_size(layout);
  for (std::int64_t n = 0; n < N; ++n)
    for (std::int64_t c = 0; c < C; ++c)
      for (std::int64_t h = 0; h < H; ++h) {
        const float* src = x.data() + n * x.stride(0) + c * x.stride(1) + h * x.stride(2);
        float* dst = y.data() + n * y.stride(0) + (c / b) * y.stride(1) + h * y.stride(2) + c % b;
        for (std::int64_t w = 0; w < W; ++w) dst[w * b] = src[w * x.stride(3)];
      }
  return y;
}

Tensor to_nchw(const Tensor& y) {
  if (y.layout() == Layout::plain || y.rank() != 5)
    throw std::invalid_argument("to_nchw expects a blocked tensor");
  const std::int64_t N = y.size(0), C = y.channels(), H = y.size(2), W = y.size(3);
  const std::int64_t b = block_size(y.layout());
  Tensor x = Tensor::empty({N, C, H, W});
  for (std::int64_t n = 0; n < N; ++n)
    for (std::int64_t c = 0; c < C; ++c)
      for (std::int64_t h = 0; h < H; ++h) {
        const float* src = y.data() + n * y.stride(0) + (c / b) * y.stride(1) + h * y.stride(2) + c % b;
        float* dst = x.data() + ((n * C + c) * H + h) * W;
        for (std::int64_t w = 0; w < W; ++w) dst[w] = src[w * y.stride(3)];
      }
  return x;
}

}  // namespace yelan
