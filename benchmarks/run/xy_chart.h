// A line-and-points chart (one or more series) as a standalone SVG, written atomically, and
// a PNG beside it when rsvg-convert is installed.
#pragma once
#include <string>
#include <vector>

namespace yelan::bench {

struct XyPoint {
  double x, y;
  std::string label;  // printed beside the point (may be empty)
};

struct XySeries {
  std::string name, colour;  // colour: an SVG colour such as "#2471a3"
  std::vector<XyPoint> points;
};

// Returns the PNG's path, or "" when no PNG was made.
std::string write_xy_chart(const std::string& svg_path, const std::string& title, const std::string& x_label,
                           const std::string& y_label, const std::vector<XySeries>& series);

}  // namespace yelan::bench
