// Command-line parsing shared by every subcommand: `--name value`, `--name=value`,
// boolean `--flag`, and positionals. Anything not declared is a usage error.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace yelan::cli {

// Exit code 2: the user asked for something malformed.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  Args(std::string command, std::vector<std::string> argv, std::set<std::string> value_options,
       std::set<std::string> flags);

  bool flag(const std::string& name) const { return flags_.count(name) > 0; }
  std::optional<std::string> value(const std::string& name) const;
  std::string value_or(const std::string& name, const std::string& fallback) const;
  int int_value_or(const std::string& name, int fallback, int min, int max) const;
  // A finite number in [min, max] (in (min, max] with min_open), or the fallback when the
  // option is absent; anything else (text, NaN, infinities, out of range) is a UsageError
  // naming the option and the range. Every number an option takes is parsed here, once.
  double number_or(const std::string& name, double fallback, double min, double max, bool min_open = false) const;
  // "on" or "off" (also 1/0, true/false, yes/no); anything else is a UsageError naming the
  // option. The option must be present.
  bool on_off(const std::string& name) const;
  std::uint64_t u64_value_or(const std::string& name, std::uint64_t fallback, std::uint64_t max) const;
  const std::vector<std::string>& positionals() const { return positionals_; }
  // Throws UsageError unless the count of positionals is within [min, max].
  void expect_positionals(std::size_t min, std::size_t max) const;

 private:
  std::string command_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::vector<std::string> positionals_;
};

// A duration: "10s", "1.5s", "500ms", "2m" (or "2min"), "1h", or a plain number of seconds;
// positive and finite. Throws UsageError naming `flag`. The one duration parser of the CLI.
double parse_duration_s(const std::string& text, const std::string& flag = "--duration");

// "a,b,,c" -> {a, b, c}: the comma lists of options such as --configs or --threads-list.
std::vector<std::string> split_list(const std::string& text);

}  // namespace yelan::cli
