#include "engine/cli/args.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace yelan::cli {

Args::Args(std::string command, std::vector<std::string> argv, std::set<std::string> value_options,
           std::set<std::string> flags)
    : command_(std::move(command)) {
  const std::string hint = " (see 'yelan " + command_ + " --help')";
  bool only_positionals = false;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (only_positionals || a.size() < 2 || a[0] != '-' || a == "-") {
      positionals_.push_back(a);
      continue;
    }
    if (a == "--") {
      only_positionals = true;
      continue;
    }
    std::string name = a, val;
    bool has_inline = false;
    if (auto eq = a.find('='); eq != std::string::npos && a.rfind("--", 0) == 0) {
      name = a.substr(0, eq);
      val = a.substr(eq + 1);
      has_inline = true;
    }
    if (value_options.count(name)) {
      if (!has_inline) {
        if (i + 1 >= argv.size()) throw UsageError("option " + name + " needs a value" + hint);
        val = argv[++i];
      }
      if (values_.count(name)) throw UsageError("option " + name + " given twice" + hint);
      values_[name] = val;
    } else if (flags.count(name)) {
      if (has_inline) throw UsageError("option " + name + " takes no value" + hint);
      flags_.insert(name);
    } else {
      throw UsageError("unknown option '" + name + "'" + hint);
    }
  }
}

std::optional<std::string> Args::value(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::value_or(const std::string& name, const std::string& fallback) const {
  return value(name).value_or(fallback);
}

int Args::int_value_or(const std::string& name, int fallback, int min, int max) const {
  auto v = value(name);
  if (!v) return fallback;
  int n = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), n);
  if (v->empty() || ec != std::errc() || ptr != v->data() + v->size() || n < min || n > max)
    throw UsageError("option " + name + " expects an integer in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + *v + "'");
  return n;
}

bool Args::on_off(const std::string& name) const {
  const std::string v = value_or(name, "");
  if (v == "on" || v == "1" || v == "true" || v == "yes") return true;
  if (v == "off" || v == "0" || v == "false" || v == "no") return false;
  throw UsageError("option " + name + " expects on or off, got '" + v + "'");
}

namespace {
std::string shown(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}
}  // namespace

double Args::number_or(const std::string& name, double fallback, double min, double max, bool min_open) const {
  auto v = value(name);
  if (!v) return fallback;
  double d = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), d);
  const bool in = ec == std::errc() && ptr == v->data() + v->size() && !v->empty() && std::isfinite(d) &&
                  (min_open ? d > min : d >= min) && d <= max;
  if (!in)
    throw UsageError("option " + name + " expects a number in " + (min_open ? "(" : "[") + shown(min) + ", " + shown(max) +
                     "], got '" + *v + "'");
  return d;
}

std::uint64_t Args::u64_value_or(const std::string& name, std::uint64_t fallback, std::uint64_t max) const {
  auto v = value(name);
  if (!v) return fallback;
  std::uint64_t n = 0;
  auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), n);
  if (v->empty() || ec != std::errc() || ptr != v->data() + v->size() || n > max)
    throw UsageError("option " + name + " expects an integer in [0, " + std::to_string(max) + "], got '" + *v + "'");
  return n;
}

void Args::expect_positionals(std::size_t min, std::size_t max) const {
  const std::size_t n = positionals_.size();
  if (n >= min && n <= max) return;
  std::string want = min == max ? std::to_string(min) : std::to_string(min) + " to " + std::to_string(max);
  throw UsageError("expected " + want + " argument(s), got " + std::to_string(n) +
                   " (see 'yelan " + command_ + " --help')");
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t end = std::min(text.find(',', at), text.size());
    if (end > at) out.push_back(text.substr(at, end - at));
    at = end + 1;
  }
  return out;
}

double parse_duration_s(const std::string& text, const std::string& flag) {
  double value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  const std::string unit(ptr, end);
  double scale = 0;
  if (unit.empty() || unit == "s") scale = 1;
  else if (unit == "ms") scale = 1e-3;
  else if (unit == "m" || unit == "min") scale = 60;
  else if (unit == "h") scale = 3600;
  const double s = value * scale;
  if (ec != std::errc() || ptr == text.data() || scale == 0 || !std::isfinite(s) || !(s > 0) || s > 1e9)
    throw UsageError(flag + " expects a positive time like 10s, 500ms, 2m or 1h, got '" + text + "'");
  return s;
}

}  // namespace yelan::cli
