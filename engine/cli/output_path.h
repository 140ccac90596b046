// An output path checked before a command starts its work, so that a run of minutes does not
// end in a write error or overwrite what it reads.
#pragma once
#include <string>
#include <vector>

namespace yelan::cli {

// Throws UsageError (exit 2) naming `flag` and `path` unless the path can be written (its
// folder exists and takes a file, it is no folder) and is none of `inputs` under any name
// (another spelling, a link, a hard link). Inputs that do not exist are passed over.
void check_output(const std::string& flag, const std::string& path, const std::vector<std::string>& inputs);

}  // namespace yelan::cli
