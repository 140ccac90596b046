#include "benchmarks/kernels/chart.h"

#include "camera/io/temp_file.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace yelan::bench {
namespace {
std::string xml_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}
}  // namespace

void write_bar_chart_svg(const std::string& path, const std::string& title, const std::vector<Bar>& bars,
                         double max_value) {
  const int label_w = 300, plot_w = 500, row_h = 18, top = 40;
  const int height = top + int(bars.size()) * row_h + 30;
  camera::TempFile tmp_file(path);
  const std::string& tmp = tmp_file.path();
  {
    std::ofstream f(tmp);
    if (!f) throw std::runtime_error("cannot write " + tmp);
    f << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << label_w + plot_w + 60 << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"10\" y=\"22\" font-size=\"15\">" << xml_escape(title) << "</text>\n";
    for (int g = 0; g <= 100; g += 25) {
      const double x = label_w + plot_w * g / 100.0;
      f << "<line x1=\"" << x << "\" y1=\"" << top - 5 << "\" x2=\"" << x << "\" y2=\"" << height - 25
        << "\" stroke=\"#ccc\"/><text x=\"" << x - 8 << "\" y=\"" << height - 10 << "\">"
        << g * max_value / 100 << "</text>\n";
    }
    if (max_value > 100) {  // mark 100 when the scale goes beyond it
      const double x100 = label_w + plot_w * 100.0 / max_value;
      f << "<line x1=\"" << x100 << "\" y1=\"" << top - 5 << "\" x2=\"" << x100 << "\" y2=\"" << height - 25
        << "\" stroke=\"#c33\" stroke-dasharray=\"4 3\"/>\n";
    }
    for (std::size_t i = 0; i < bars.size(); ++i) {
      const double y = top + double(i) * row_h;
      const double w = plot_w * std::clamp(bars[i].value / max_value, 0.0, 1.0);
      char val[32];
      std::snprintf(val, sizeof val, "%.1f", bars[i].value);
      f << "<text x=\"" << label_w - 6 << "\" y=\"" << y + 13 << "\" text-anchor=\"end\">"
        << xml_escape(bars[i].label) << "</text><rect x=\"" << label_w << "\" y=\"" << y + 2 << "\" width=\"" << w
        << "\" height=\"" << row_h - 4 << "\" fill=\"#4a7ab5\"/><text x=\"" << label_w + w + 4 << "\" y=\""
        << y + 13 << "\">" << val << "</text>\n";
    }
    f << "</svg>\n";
    if (!f.flush()) throw std::runtime_error("write failed: " + tmp);
  }
  tmp_file.commit();
}

}  // namespace yelan::bench
