// train::mask_picture_rgb: each pixel's class (both, stage 1 alone, truth alone, neither) in
// its colour over the TORE's grey, the mask's cells spread over the downscaled pixels.
#include <catch2/catch.hpp>

#include "engine/train/mask_picture.h"

using yelan::train::MaskPictureColours;
using yelan::train::mask_picture_rgb;

TEST_CASE("mask picture: stage 1 against the truth in three colours over the events", "[train][pictures]") {
  const int h = 2, w = 5, k = 2, down = 2;  // a 1 x 2 mask; the fifth column has no cell
  std::vector<float> tore(std::size_t(2 * k * h * w), 0.f);
  tore[0] = 1.f;                          // pixel (0,0): a positive event just now
  tore[std::size_t(k * h * w) + 6] = 0.5f;  // pixel (1,1): a negative one, half as bright
  tore[std::size_t(1 * h * w) + 2] = 1.f;   // an older plane: not shown
  const std::vector<std::uint8_t> truth = {1, 1, 0, 0, 1,  //
                                           0, 1, 1, 0, 0};
  const std::vector<float> keep = {0.7f, 0.f};  // cell 0 (columns 0-1) dancer, cell 1 (2-3) not
  const auto rgb = mask_picture_rgb(tore.data(), k, h, w, truth.data(), keep.data(), 1, 2, down);
  REQUIRE(rgb.size() == std::size_t(3 * h * w));
  const auto px = [&](int y, int x, int c) { return int(rgb[std::size_t(3 * (y * w + x) + c)]); };
  const int g1 = 153, g05 = 77;  // 60% of 255 and of 127.5, rounded
  for (int c = 0; c < 3; ++c) {
    CHECK(px(0, 0, c) == (MaskPictureColours::both[c] + g1) / 2);    // both, over a bright event
    CHECK(px(0, 1, c) == MaskPictureColours::both[c] / 2);          // both, no event
    CHECK(px(1, 0, c) == MaskPictureColours::net_only[c] / 2);      // stage 1 alone
    CHECK(px(1, 1, c) == (MaskPictureColours::both[c] + g05) / 2);  // both, over a dim event
    CHECK(px(1, 2, c) == MaskPictureColours::truth_only[c] / 2);    // the truth alone
    CHECK(px(0, 2, c) == 0);                                         // neither; the old plane unseen
    CHECK(px(0, 4, c) == MaskPictureColours::truth_only[c] / 2);    // no cell: stage 1 says nothing
    CHECK(px(1, 4, c) == 0);
  }
}
