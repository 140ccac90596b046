#include "benchmarks/run/xy_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "camera/io/temp_file.h"
#include "engine/subprocess.h"

namespace yelan::bench {

namespace {

std::vector<double> ticks(double lo, double hi) {
  const double raw = (hi - lo) / 5;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * mag) {
      step = m * mag;
      break;
    }
  std::vector<double> out;
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push_back(v);
  return out;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return b;
}

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) o += c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '&' ? "&amp;" : std::string(1, c);
  return o;
}

}  // namespace

std::string write_xy_chart(const std::string& svg_path, const std::string& title, const std::string& x_label,
                           const std::string& y_label, const std::vector<XySeries>& series) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& s : series)
    for (const auto& p : s.points) {
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
  if (x0 > x1) throw std::invalid_argument("chart " + svg_path + ": no points");
  const double xpad = std::max(1e-9, (x1 - x0) * 0.08), ypad = std::max(1e-9, (y1 - y0) * 0.1);
  x0 -= xpad, x1 += xpad * 2, y0 -= ypad, y1 += ypad;
  if (x0 > 0 && x0 < (x1 - x0)) x0 = 0;
  const double W = 720, H = 440, L = 70, R = 30, T = 50, B = 60;
  auto X = [&](double v) { return L + (v - x0) / (x1 - x0) * (W - L - R); };
  auto Y = [&](double v) { return H - B - (v - y0) / (y1 - y0) * (H - T - B); };
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(1);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << W / 2 << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">" << esc(title) << "</text>\n";
  for (double t : ticks(x0, x1))
    o << "<line x1=\"" << X(t) << "\" y1=\"" << T << "\" x2=\"" << X(t) << "\" y2=\"" << H - B << "\" stroke=\"#eee\"/><text x=\""
      << X(t) << "\" y=\"" << H - B + 16 << "\" text-anchor=\"middle\">" << num(t) << "</text>\n";
  for (double t : ticks(y0, y1))
    o << "<line x1=\"" << L << "\" y1=\"" << Y(t) << "\" x2=\"" << W - R << "\" y2=\"" << Y(t) << "\" stroke=\"#eee\"/><text x=\""
      << L - 6 << "\" y=\"" << Y(t) + 4 << "\" text-anchor=\"end\">" << num(t) << "</text>\n";
  o << "<line x1=\"" << L << "\" y1=\"" << H - B << "\" x2=\"" << W - R << "\" y2=\"" << H - B << "\" stroke=\"black\"/>"
    << "<line x1=\"" << L << "\" y1=\"" << T << "\" x2=\"" << L << "\" y2=\"" << H - B << "\" stroke=\"black\"/>\n"
    << "<text x=\"" << (L + W - R) / 2 << "\" y=\"" << H - 18 << "\" text-anchor=\"middle\">" << esc(x_label) << "</text>\n"
    << "<text transform=\"translate(18," << (T + H - B) / 2 << ") rotate(-90)\" text-anchor=\"middle\">" << esc(y_label)
    << "</text>\n";
  // Labels of points that land close together (equal times) stack downwards instead of
  // printing over each other.
  std::vector<std::pair<double, double>> placed;
  auto label_y = [&](double x, double y) {
    for (bool moved = true; moved;) {
      moved = false;
      for (const auto& [px, py] : placed)
        if (std::abs(px - x) < 70 && std::abs(py - y) < 13) {
          y = py + 13;
          moved = true;
        }
    }
    placed.push_back({x, y});
    return y;
  };
  for (std::size_t i = 0; i < series.size(); ++i) {
    const XySeries& s = series[i];
    o << "<polyline fill=\"none\" stroke=\"" << s.colour << "\" stroke-width=\"1.5\" points=\"";
    for (const auto& p : s.points) o << X(p.x) << "," << Y(p.y) << " ";
    o << "\"/>\n";
    for (const auto& p : s.points) {
      o << "<circle cx=\"" << X(p.x) << "\" cy=\"" << Y(p.y) << "\" r=\"4\" fill=\"" << s.colour << "\"/>";
      if (!p.label.empty())
        o << "<text x=\"" << X(p.x) + 7 << "\" y=\"" << label_y(X(p.x) + 7, Y(p.y) - 7) << "\">" << esc(p.label) << "</text>";
      o << "\n";
    }
    o << "<circle cx=\"" << W - R - 190 << "\" cy=\"" << T + 12 + 18 * i << "\" r=\"5\" fill=\"" << s.colour << "\"/><text x=\""
      << W - R - 180 << "\" y=\"" << T + 16 + 18 * i << "\">" << esc(s.name) << "</text>\n";
  }
  o << "</svg>\n";
  camera::write_file_atomically(svg_path, o.str());
  if (svg_path.size() < 4 || svg_path.substr(svg_path.size() - 4) != ".svg") return "";
  const std::string png = svg_path.substr(0, svg_path.size() - 4) + ".png";
  // The PNG is a convenience for READMEs; the SVG is the result. rsvg-convert overwrites a
  // temporary file of ours (created exclusively), removed unless it succeeds.
  camera::TempFile tmp(png);
  // Absolute paths: one starting with '-' would read as an option.
  const std::string abs_svg = std::filesystem::absolute(svg_path).string(), abs_png = std::filesystem::absolute(tmp.path()).string();
  if (!run_program(Program({"rsvg-convert", "-o", abs_png, abs_svg})).ok()) return "";
  tmp.commit();
  return png;
}

}  // namespace yelan::bench
