// A horizontal bar chart as a standalone SVG file (written atomically).
#pragma once
#include <string>
#include <vector>

namespace yelan::bench {

struct Bar {
  std::string label;
  double value;
};

void write_bar_chart_svg(const std::string& path, const std::string& title, const std::vector<Bar>& bars,
                         double max_value);

}  // namespace yelan::bench
