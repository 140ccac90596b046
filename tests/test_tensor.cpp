#include <catch2/catch.hpp>

#include <cstdint>
#include <stdexcept>

#include "engine/tensor.h"

using yelan::Dims;
using yelan::Layout;
using yelan::Tensor;

namespace {
bool aligned64(const void* p) { return reinterpret_cast<std::uintptr_t>(p) % 64 == 0; }
void iota(const Tensor& t) {
  float* p = t.data();
  for (std::int64_t i = 0; i < t.numel(); ++i) p[i] = float(i);
}
}  // namespace

TEST_CASE("owning tensors are 64-byte aligned with row-major strides", "[engine][tensor]") {
  for (std::int64_t n : {1, 3, 7, 17, 33}) {
    Tensor t = Tensor::empty({n, 3, 5});
    CHECK(aligned64(t.data()));
    CHECK(t.rank() == 3);
    CHECK(t.shape() == Dims{n, 3, 5});
    CHECK(t.strides() == Dims{15, 5, 1});
    CHECK(t.numel() == n * 15);
    CHECK(t.is_contiguous());
    CHECK(t.owns_memory());
  }
  Tensor z = Tensor::zeros({0, 4});
  CHECK(z.numel() == 0);
  CHECK(aligned64(z.data()));
  Tensor zs = Tensor::zeros({2, 3});
  for (std::int64_t i = 0; i < 2; ++i)
    for (std::int64_t j = 0; j < 3; ++j) CHECK(zs.at({i, j}) == 0.f);
}

TEST_CASE("bad shapes and indices are refused with exceptions", "[engine][tensor]") {
  CHECK_THROWS_AS(Tensor::empty({-1, 3}), std::invalid_argument);
  CHECK_THROWS_AS(Tensor::empty({1 << 30, 1 << 30, 1 << 30}), std::invalid_argument);
  CHECK_THROWS_AS((Dims{1, 2, 3, 4, 5, 6, 7}), std::invalid_argument);
  Tensor t = Tensor::zeros({2, 3});
  CHECK_THROWS_AS(t.at({2, 0}), std::out_of_range);
  CHECK_THROWS_AS(t.at({0, -1}), std::out_of_range);
  CHECK_THROWS_AS(t.at({0}), std::out_of_range);
  CHECK_THROWS_AS(t.slice(1, 2, 4), std::out_of_range);
  CHECK_THROWS_AS(t.slice(2, 0, 1), std::out_of_range);
  CHECK_THROWS_AS(t.reshape({7}), std::invalid_argument);
}

TEST_CASE("slices and selects are views sharing memory", "[engine][tensor]") {
  Tensor t = Tensor::empty({4, 5, 6});
  iota(t);
  Tensor s = t.slice(1, 1, 4);  // [4, 3, 6]
  CHECK(s.shape() == Dims{4, 3, 6});
  CHECK(s.strides() == t.strides());
  CHECK_FALSE(s.is_contiguous());
  CHECK(s.at({2, 0, 3}) == t.at({2, 1, 3}));
  s.at({2, 0, 3}) = -5.f;
  CHECK(t.at({2, 1, 3}) == -5.f);

  Tensor row = t.select(0, 3);  // [5, 6]
  CHECK(row.shape() == Dims{5, 6});
  CHECK(row.at({4, 5}) == t.at({3, 4, 5}));
  CHECK(row.is_contiguous());

  Tensor col = t.select(2, 2);  // [4, 5] with strides [30, 6]
  CHECK(col.strides() == Dims{30, 6});
  CHECK(col.at({1, 1}) == t.at({1, 1, 2}));
}

TEST_CASE("views keep the storage alive after the original goes", "[engine][tensor]") {
  Tensor view;
  {
    Tensor t = Tensor::empty({3, 3});
    iota(t);
    view = t.slice(0, 1, 3);
    CHECK(t.use_count() == 2);
  }
  CHECK(view.use_count() == 1);
  CHECK(view.at({1, 2}) == 8.f);
}

TEST_CASE("reshape, clone, fill and copy between strided views", "[engine][tensor]") {
  Tensor t = Tensor::empty({2, 3, 4});
  iota(t);
  Tensor r = t.reshape({6, 4});
  CHECK(r.at({5, 3}) == 23.f);
  CHECK(r.data() == t.data());
  CHECK_THROWS_AS(t.slice(2, 0, 3).reshape({18}), std::invalid_argument);

  Tensor c = t.slice(2, 1, 3).clone();  // [2, 3, 2] contiguous copy
  CHECK(c.is_contiguous());
  CHECK(c.at({1, 2, 1}) == t.at({1, 2, 2}));
  c.at({0, 0, 0}) = 100.f;
  CHECK(t.at({0, 0, 1}) == 1.f);

  Tensor dst = Tensor::zeros({3, 2, 4}).slice(2, 0, 2);  // strided destination
  Tensor src = t.slice(0, 0, 1).reshape({3, 4}).slice(1, 2, 4);  // [3, 2] strided source
  Tensor dst2 = Tensor::zeros({3, 2});
  dst2.copy_from(src);
  CHECK(dst2.at({2, 1}) == t.at({0, 2, 3}));
  CHECK_THROWS_AS(dst.copy_from(src), std::invalid_argument);

  Tensor f = Tensor::zeros({3, 4});
  f.slice(1, 1, 3).fill(2.f);
  CHECK(f.at({2, 0}) == 0.f);
  CHECK(f.at({2, 1}) == 2.f);
  CHECK(f.at({2, 3}) == 0.f);
}

TEST_CASE("blocked layouts round-trip NCHW for odd channel counts", "[engine][tensor]") {
  for (Layout layout : {Layout::nchw4c, Layout::nchw8c, Layout::nchw16c}) {
    for (std::int64_t C : {1, 3, 13, 16, 17, 33}) {
      const std::int64_t b = yelan::block_size(layout);
      INFO(yelan::layout_name(layout) << " C " << C);
      Tensor x = Tensor::empty({2, C, 7, 5});
      iota(x);
      Tensor y = yelan::to_blocked(x, layout);
      CHECK(y.layout() == layout);
      CHECK(y.channels() == C);
      CHECK(y.shape() == Dims{2, (C + b - 1) / b, 7, 5, b});
      CHECK(y.stride(4) == 1);
      for (std::int64_t n = 0; n < 2; ++n)
        for (std::int64_t c = 0; c < C; ++c)
          for (std::int64_t h = 0; h < 7; h += 3)
            for (std::int64_t w = 0; w < 5; w += 2) REQUIRE(y.at_nchw(n, c, h, w) == x.at({n, c, h, w}));
      for (std::int64_t c = C; c < y.size(1) * b; ++c)  // padding lanes stay zero
        REQUIRE(y.at({1, c / b, 6, 4, c % b}) == 0.f);
      Tensor back = yelan::to_nchw(y);
      REQUIRE(back.shape() == x.shape());
      for (std::int64_t i = 0; i < x.numel(); ++i) REQUIRE(back.data()[i] == x.data()[i]);
      CHECK_THROWS_AS(y.at_nchw(0, C, 0, 0), std::out_of_range);
    }
  }
  CHECK_THROWS_AS(yelan::to_blocked(Tensor::zeros({2, 3}), Layout::nchw8c), std::invalid_argument);
  CHECK_THROWS_AS(yelan::to_nchw(Tensor::zeros({1, 1, 1, 1})), std::invalid_argument);
}

TEST_CASE("a channel-block slice of a blocked tensor keeps the logical channel count", "[engine][tensor]") {
  Tensor y = Tensor::empty_blocked(1, 37, 3, 3, Layout::nchw16c);  // blocks of 16, 16, 5
  CHECK(y.slice(1, 0, 2).channels() == 32);
  CHECK(y.slice(1, 2, 3).channels() == 5);
  CHECK(y.slice(1, 1, 3).channels() == 21);
}
