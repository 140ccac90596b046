#include "engine/cli/cli.h"

#include <stdexcept>

#include "camera/io/format_error.h"
#include "engine/cli/args.h"
#include "engine/cli/commands.h"
#include "engine/threads.h"
#include "engine/model_config.h"
#include "kernels/cpu.h"
#include "weights_tools/parse_json.h"
#include "weights_tools/weights_file.h"

namespace yelan::cli {
namespace {

const char* kGlobalHelp =
    "usage: yelan [--threads N] [--isa scalar|avx2|avx512|neon] COMMAND [ARGS...]\n"
    "       yelan --version | --help\n"
    "\n"
    "Event-camera 3D human pose estimation (YeLan) on our own CPU kernels.\n"
    "\n"
    "global options (anywhere on the line):\n"
    "  --threads N   OpenMP threads (default: YELAN_THREADS, else all cores)\n"
    "  --isa NAME    force a kernel ISA (default: YELAN_ISA, else the best this CPU has)\n"
    "  --version     version, chosen ISA, CPU features, library versions\n"
    "\n"
    "commands:\n";

std::string global_help() {
  std::string s = kGlobalHelp;
  for (const Command& c : commands()) {
    std::string name = "  " + c.name;
    name.resize(12, ' ');
    s += name + c.summary + (c.handler ? "" : "  [not built yet]") + "\n";
  }
  s += "\n'yelan COMMAND --help' describes one command. Exit codes: 0 ok, 1 runtime error,\n"
       "2 bad usage or bad input.\n";
  return s;
}

// Pulls --threads/--isa (and their =value forms) out of argv, applying them.
std::vector<std::string> apply_global_options(const std::vector<std::string>& argv) {
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    std::string a = argv[i], val;
    bool is_threads = a == "--threads" || a.rfind("--threads=", 0) == 0;
    bool is_isa = a == "--isa" || a.rfind("--isa=", 0) == 0;
    if (a == "--") {  // everything after belongs to the command
      rest.insert(rest.end(), argv.begin() + i, argv.end());
      break;
    }
    if (!is_threads && !is_isa) {
      rest.push_back(a);
      continue;
    }
    if (auto eq = a.find('='); eq != std::string::npos) {
      val = a.substr(eq + 1);
      a = a.substr(0, eq);
    } else if (i + 1 < argv.size()) {
      val = argv[++i];
    } else {
      throw UsageError("option " + a + " needs a value");
    }
    if (is_threads) {
      auto n = parse_thread_count(val);
      if (!n) throw UsageError("--threads expects an integer in [1, 1024], got '" + val + "'");
      set_threads(*n);
    } else {
      auto isa = kernels::parse_isa(val);
      if (!isa) throw UsageError("--isa expects scalar, avx2, avx512 or neon, got '" + val + "'");
      if (!kernels::isa_supported(*isa))
        throw UsageError("--isa " + val + " is not supported on this CPU (available: " +
                         kernels::supported_isas() + ")");
      kernels::set_isa(*isa);
    }
  }
  return rest;
}

int dispatch(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  init_threads_from_env();
  kernels::active_isa();  // validates YELAN_ISA up front
  std::vector<std::string> args = apply_global_options(argv);
  if (args.empty()) {
    err << global_help();
    return kUsageError;
  }
  const std::string& first = args[0];
  if (first == "--help" || first == "-h" || first == "help") {
    out << global_help();
    return kOk;
  }
  if (first == "--version" || first == "-V") {
    out << version_text();
    return kOk;
  }
  if (first.rfind("-", 0) == 0) throw UsageError("unknown option '" + first + "' (see 'yelan --help')");
  for (const Command& c : commands()) {
    if (c.name != first) continue;
    std::vector<std::string> rest(args.begin() + 1, args.end());
    for (const std::string& a : rest)
      if (a == "--help" || a == "-h") {
        out << c.usage;
        if (!c.handler) out << "\nnot built yet: comes with " << c.planned << ".\n";
        return kOk;
      }
    if (!c.handler) {
      err << "yelan " << c.name << ": not built yet (comes with " << c.planned << ")\n";
      return kRuntimeError;
    }
    return c.handler(rest, out, err);
  }
  throw UsageError("unknown command '" + first + "' (see 'yelan --help')");
}

}  // namespace

std::string printable(const std::string& text) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (const unsigned char c : text) {
    if (c >= 0x20 && c != 0x7f) {
      out += char(c);
    } else if (c == '\n') {
      out += "\n";  // multi-line messages keep their lines
    } else {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

int run(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  // One mapping from error kind to exit code: bad usage or bad input (a malformed file,
  // weights or config) is 2, anything else that failed at run time is 1. Messages may quote
  // text from files: control characters are shown escaped, never sent to the terminal.
  auto fail = [&](const std::exception& e, int code) {
    err << "yelan: error: " << printable(e.what()) << "\n";
    return code;
  };
  try {
    return dispatch(argv, out, err);
  } catch (const UsageError& e) {
    return fail(e, kUsageError);
  } catch (const std::invalid_argument& e) {
    return fail(e, kUsageError);
  } catch (const camera::FormatError& e) {
    return fail(e, kUsageError);
  } catch (const weights::WeightsError& e) {
    return fail(e, kUsageError);
  } catch (const weights::JsonError& e) {
    return fail(e, kUsageError);
  } catch (const ConfigError& e) {
    return fail(e, kUsageError);
  } catch (const std::exception& e) {
    return fail(e, kRuntimeError);
  }
}

}  // namespace yelan::cli
