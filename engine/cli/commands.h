// The subcommand table. A command whose handler is empty is announced in --help with the
// work that will bring it, and running it is a runtime error (exit 1), never a silent no-op.
#pragma once
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace yelan::cli {

struct Command {
  std::string name;
  std::string summary;
  std::string usage;  // full text of `yelan NAME --help`
  std::function<int(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)> handler;
  std::string planned;  // for commands not built yet: what brings them
};

const std::vector<Command>& commands();

}  // namespace yelan::cli
