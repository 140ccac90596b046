// Stage 1's masks as yelan run uses them: the cut of every channel in one pass, and the
// growth of a mask (run.mask_grow), against brute force on odd shapes. In the engine's test
// binary so that the sanitizer run covers them (test_input_path's recordings it leaves out).
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "engine/input.h"
#include "layers/buffer.h"

TEST_CASE("grow_mask: a pixel is kept when one within r of it (a square) was, on odd shapes", "[engine]") {
  std::mt19937 rng(7);
  for (const auto& [h, w] : {std::pair{1, 1}, {5, 3}, {7, 11}, {13, 2}, {9, 17}})
    for (const int r : {0, 1, 2, 4, 20}) {
      INFO(h << " x " << w << ", r " << r);
      std::vector<float> m(std::size_t(h) * w);
      for (auto& v : m) v = rng() % 9 == 0 ? 1.f : 0.f;
      std::vector<float> got = m;
      yelan::input::grow_mask(got, h, w, r);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          float want = 0;
          for (int yy = std::max(0, y - r); yy <= std::min(h - 1, y + r); ++yy)
            for (int xx = std::max(0, x - r); xx <= std::min(w - 1, x + r); ++xx) want = std::max(want, m[std::size_t(yy) * w + xx]);
          REQUIRE(got[std::size_t(y) * w + x] == want);
        }
    }
  // The pipeline boxes a grown mask by growing the mask's box: the same box, clipped.
  for (const int r : {0, 1, 3}) {
    std::vector<float> m(7 * 11, 0.f);
    m[2 * 11 + 1] = m[4 * 11 + 8] = 1;
    yelan::input::grow_mask(m, 7, 11, r);
    int x0 = 11, y0 = 7, x1 = 0, y1 = 0;
    for (int y = 0; y < 7; ++y)
      for (int x = 0; x < 11; ++x)
        if (m[std::size_t(y) * 11 + x] != 0) x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
    CHECK(x0 == std::max(1 - r, 0));
    CHECK(y0 == std::max(2 - r, 0));
    CHECK(x1 == std::min(9 + r, 11));
    CHECK(y1 == std::min(5 + r, 7));
  }
  // One pixel grows into a (2r + 1)-square, clipped at the border.
  std::vector<float> one(7 * 9, 0.f);
  one[3 * 9 + 1] = 1;
  yelan::input::grow_mask(one, 7, 9, 2);
  CHECK(std::count(one.begin(), one.end(), 1.f) == 5 * 4);
  std::vector<float> wrong(10);
  CHECK_THROWS_AS(yelan::input::grow_mask(wrong, 3, 3, 1), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::grow_mask(one, 7, 9, -1), std::invalid_argument);
}

TEST_CASE("mask_cut_all: every channel's mask_cut, kept count and box in one pass, over a range of channels", "[engine]") {
  // 21 channels: a full block and five of the next; the padding lanes hold large logits that
  // must never be read as masks. Channel 3 keeps nothing, channel 19 everything.
  yelan::layers::ActBuf buf;
  const yelan::layers::Act a = buf.get(2, 21, 7, 11);
  std::mt19937 rng(11);
  std::normal_distribution<float> logit(-2.f, 2.f);
  for (int n = 0; n < 2; ++n)
    for (int cb = 0; cb < 2; ++cb)
      for (std::size_t i = 0; i < a.pixels(); ++i)
        for (int l = 0; l < 16; ++l) {
          const int c = cb * 16 + l;
          float& v = a.data[((std::size_t(n) * 2 + cb) * a.pixels() + i) * 16 + l];
          v = c >= 21 ? 10.f : c == 3 ? -20.f : c == 19 ? 20.f : logit(rng);
        }
  // Channels first..end-1 (end -1: all 21; 4 ends inside the first block, 18 inside the second).
  for (const auto& [first, end] : std::vector<std::pair<int, int>>{{0, -1}, {1, -1}, {17, -1}, {0, 4}, {1, 18}, {17, 18}, {5, 5}})
    for (const float cut : {0.1f, 0.5f}) {
      INFO("first " << first << ", end " << end << ", cut " << cut);
      std::vector<std::vector<float>> keep(25, std::vector<float>(3, 1.f));  // stale entries: replaced or cleared
      std::vector<yelan::input::MaskExtent> ext;
      yelan::input::mask_cut_all(a, 1, cut, keep, ext, first, end);
      REQUIRE(keep.size() == 21);
      REQUIRE(ext.size() == 21);
      for (int c = 0; c < 21; ++c) {
        INFO("channel " << c);
        if (c < first || (end >= 0 && c >= end)) {
          CHECK(keep[std::size_t(c)].empty());
          CHECK(ext[std::size_t(c)].kept == 0);
          continue;
        }
        std::vector<float> want;
        yelan::input::mask_cut(a, 1, c, want, cut);
        REQUIRE(keep[std::size_t(c)] == want);
        std::size_t kept = 0;
        int x0 = a.w, y0 = a.h, x1 = 0, y1 = 0;
        for (int y = 0; y < a.h; ++y)
          for (int x = 0; x < a.w; ++x)
            if (want[std::size_t(y) * a.w + x] != 0)
              ++kept, x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
        const auto& e = ext[std::size_t(c)];
        CHECK(e.kept == kept);
        if (kept == 0) x0 = y0 = 0;
        CHECK((e.x0 == x0 && e.y0 == y0 && e.x1 == x1 && e.y1 == y1));
      }
      if (first <= 3) CHECK(ext[3].kept == 0);
      CHECK(ext[19].kept == (first <= 19 && (end < 0 || end > 19) ? a.pixels() : 0));
    }
  std::vector<std::vector<float>> keep;
  std::vector<yelan::input::MaskExtent> ext;
  CHECK_THROWS_AS(yelan::input::mask_cut_all(a, 2, 0.5f, keep, ext), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::mask_cut_all(a, 0, 1.f, keep, ext), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::mask_cut_all(a, 0, 0.5f, keep, ext, 22), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::mask_cut_all(a, 0, 0.5f, keep, ext, 0, 22), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::mask_cut_all(a, 0, 0.5f, keep, ext, 5, 4), std::invalid_argument);
}

TEST_CASE("mask_stage2_input: inside and outside the mask, the outside part within the grown box; bad shapes refused", "[engine]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.1f, 1.f);
  for (const auto& [h, w] : {std::pair{5, 3}, {7, 11}, {13, 2}})
    for (const int c : {2, 6, 8})
      for (const int margin : {0, 1, 3})
        for (const bool empty : {false, true}) {
          INFO(h << " x " << w << ", " << c << " channels, margin " << margin << (empty ? ", empty mask" : ""));
          yelan::layers::ActBuf a;
          a.resize(2, 2 * c, h, w);
          for (std::size_t i = 0; i < a.act.floats(); ++i) a.act.data[i] = (i % 16) < std::size_t(c) ? u(rng) : 0.f;
          const std::vector<float> before(a.act.data, a.act.data + a.act.floats());
          std::vector<float> keep(std::size_t(h) * w, 0.f);
          int x0 = w, y0 = h, x1 = 0, y1 = 0;
          if (!empty)
            for (int y = 0; y < h; ++y)
              for (int x = 0; x < w; ++x)
                if (rng() % 5 == 0 && x > 0 && y > 0) {
                  keep[std::size_t(y) * w + x] = 1;
                  x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
                }
          yelan::input::mask_stage2_input(a.act, 1, keep, true, margin);
          for (std::size_t i = 0; i < std::size_t(h) * w * 16; ++i) REQUIRE(a.act.data[i] == before[i]);  // frame 0 untouched
          const float* f = a.act.data + std::size_t(h) * w * 16;
          const float* b = before.data() + std::size_t(h) * w * 16;
          for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
              const std::size_t p = std::size_t(y) * w + x;
              const bool region = margin == 0 || (x1 > 0 && x >= x0 - margin && x < x1 + margin && y >= y0 - margin && y < y1 + margin);
              for (int l = 0; l < c; ++l) {
                REQUIRE(f[p * 16 + l] == b[p * 16 + l] * keep[p]);
                REQUIRE(f[p * 16 + c + l] == (region ? b[p * 16 + l] * (1 - keep[p]) : 0.f));
              }
              for (int l = 2 * c; l < 16; ++l) REQUIRE(f[p * 16 + l] == 0.f);
            }
          // Without `outside`, apply_mask.
          yelan::layers::ActBuf g;
          g.resize(1, c, h, w);
          for (std::size_t i = 0; i < g.act.floats(); ++i) g.act.data[i] = (i % 16) < std::size_t(c) ? u(rng) : 0.f;
          std::vector<float> want(g.act.data, g.act.data + g.act.floats());
          yelan::layers::ActBuf g2;
          g2.resize(1, c, h, w);
          std::copy(want.begin(), want.end(), g2.act.data);
          yelan::input::apply_mask(g2.act, 0, keep);
          yelan::input::mask_stage2_input(g.act, 0, keep, false, margin);
          REQUIRE(std::equal(g.act.data, g.act.data + g.act.floats(), g2.act.data));
        }
  yelan::layers::ActBuf odd, wide;
  odd.resize(1, 7, 4, 4);
  wide.resize(1, 18, 4, 4);
  const std::vector<float> keep(16, 1.f), short_keep(15, 1.f);
  CHECK_THROWS_AS(yelan::input::mask_stage2_input(odd.act, 0, keep, true, 0), std::invalid_argument);
  CHECK_THROWS_AS(yelan::input::mask_stage2_input(wide.act, 0, keep, true, 0), std::invalid_argument);
  yelan::layers::ActBuf ok;
  ok.resize(1, 12, 4, 4);
  CHECK_THROWS_AS(yelan::input::mask_stage2_input(ok.act, 0, short_keep, true, 0), std::invalid_argument);
  CHECK_NOTHROW(yelan::input::mask_stage2_input(ok.act, 0, keep, true, 0));
}
