// train::add_mask_overlap: the IoU at the net's size, off the true outline's edge and at the
// sensor's pixels, counted by hand on a shifted square with two false cells far from it.
#include <catch2/catch.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "engine/train/mask_overlap.h"

using yelan::train::MaskOverlap;
using yelan::train::add_mask_overlap;
using yelan::train::measured_iou;

TEST_CASE("mask overlap: the IoU, and the IoU off the true outline's edge", "[train]") {
  const int mh = 5, mw = 6, down = 2, sw = mw * down;
  // The truth: a 3 x 3 square (rows 1-3, columns 1-3 of the cells) at the cells' centre
  // pixels, and a pixel off every centre that the count must not see.
  std::vector<std::uint8_t> truth(std::size_t(mh * down * sw), 0);
  for (int y = 1; y <= 3; ++y)
    for (int x = 1; x <= 3; ++x) truth[std::size_t((y * down + 1) * sw + x * down + 1)] = 1;
  truth[std::size_t(0 * sw + 10)] = 1;  // cell (0, 5)'s corner, not its centre
  // Stage 1: the square a column to the right, and cells (0, 5) and (4, 5).
  std::vector<float> keep(std::size_t(mh * mw), 0.f);
  for (int y = 1; y <= 3; ++y)
    for (int x = 2; x <= 4; ++x) keep[std::size_t(y * mw + x)] = 1.f;
  keep[std::size_t(0 * mw + 5)] = 0.3f;
  keep[std::size_t(4 * mw + 5)] = 1.f;
  MaskOverlap m;
  add_mask_overlap(m, truth.data(), sw, keep.data(), mh, mw, down);
  CHECK(m.inter == 6);        // rows 1-3, columns 2-3
  CHECK(m.uni == 9 + 9 - 6 + 2);
  CHECK(m.iou() == Approx(6.0 / 14.0));
  // Off the edge: the square's centre cell (both) and column 5 (two false cells); every other
  // cell touches the outline.
  CHECK(m.inter_off_edge == 1);
  CHECK(m.uni_off_edge == 3);
  CHECK(m.iou_off_edge() == Approx(1.0 / 3.0));
  // At the sensor's pixels: 11 kept cells of 4 pixels each (0.3 > 0 keeps cell (0, 5)), 10
  // true pixels, of which the six centres in columns 2-3 and the corner in cell (0, 5) are kept.
  CHECK(m.inter_px == 7);
  CHECK(m.uni_px == 44 + 10 - 7);
  CHECK(m.iou_px() == Approx(7.0 / 47.0));
  // Counts add over frames, and a difference is one frame's share.
  MaskOverlap two = m;
  add_mask_overlap(two, truth.data(), sw, keep.data(), mh, mw, down);
  const MaskOverlap second = two - m;
  CHECK(second.inter == m.inter);
  CHECK(second.uni_off_edge == m.uni_off_edge);
  CHECK(second.uni_px == m.uni_px);
  CHECK(two.iou() == Approx(m.iou()));
  // Nothing in either: no union, IoU 0 rather than a division by zero.
  MaskOverlap none;
  const std::vector<std::uint8_t> empty_truth(truth.size(), 0);
  const std::vector<float> empty_keep(keep.size(), 0.f);
  add_mask_overlap(none, empty_truth.data(), sw, empty_keep.data(), mh, mw, down);
  CHECK(none.uni == 0);
  CHECK(none.iou() == 0);
  CHECK(none.iou_off_edge() == 0);
  CHECK(none.iou_px() == 0);
}

TEST_CASE("mask overlap: a key with no dancer pixel and no kept one has no IoU", "[train]") {
  const int mh = 3, mw = 4, down = 2, sw = mw * down;
  std::vector<std::uint8_t> truth(std::size_t(mh * down * sw), 0);
  std::vector<float> keep(std::size_t(mh * mw), 0.f);
  std::map<std::string, MaskOverlap> by;
  // "hidden": the dancer wholly behind furniture, and stage 1 keeps nothing.
  add_mask_overlap(by["hidden"], truth.data(), sw, keep.data(), mh, mw, down);
  // "seen": one true cell at its centre pixel, kept; "missed": a true cell, nothing kept.
  truth[std::size_t(1 * sw + 1)] = 1;
  add_mask_overlap(by["missed"], truth.data(), sw, keep.data(), mh, mw, down);
  keep[0] = 1.f;
  add_mask_overlap(by["seen"], truth.data(), sw, keep.data(), mh, mw, down);
  const auto cells = measured_iou(by);
  CHECK(cells.count("hidden") == 0);
  REQUIRE(cells.count("missed") == 1);
  CHECK(cells.at("missed") == 0);
  REQUIRE(cells.count("seen") == 1);
  CHECK(cells.at("seen") == Approx(1.0));
  const auto px = measured_iou(by, true);
  CHECK(px.count("hidden") == 0);
  CHECK(px.at("missed") == 0);
  CHECK(px.at("seen") == Approx(1.0 / 4.0));  // one true pixel of the kept cell's four
}
