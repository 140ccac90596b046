#include "engine/cli/output_path.h"

#include <filesystem>
#include <stdexcept>

#include "camera/io/temp_file.h"
#include "engine/cli/args.h"

namespace yelan::cli {

void check_output(const std::string& flag, const std::string& path, const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) throw UsageError(flag + ": empty path");
  if (fs::is_directory(path, ec)) throw UsageError(flag + " " + path + ": is a directory");
  const fs::path parent = fs::absolute(path, ec).parent_path();
  if (!fs::is_directory(parent, ec)) throw UsageError(flag + " " + path + ": no directory " + parent.string());
  // Root passes access(2) everywhere: creating a file is the real test. A TempFile's name
  // cannot be guessed, so no link planted beside the output stops the command; the leading
  // dot keeps it apart from the output's own temporary file.
  std::string probe_name = ".";  // appended, not "." + ...: GCC 12 warns falsely on that (-Wrestrict)
  probe_name += fs::path(path).filename().string();
  try {
    const camera::TempFile probe((parent / probe_name).string());
  } catch (const std::runtime_error& e) {
    const std::string why = e.what();  // "cannot create ... beside PROBE: reason": the reason only
    throw UsageError(flag + " " + path + ": cannot write in " + parent.string() + " (" + why.substr(why.rfind(": ") + 2) + ")");
  }
  for (const auto& in : inputs)
    if (fs::exists(in, ec) && fs::exists(path, ec) && fs::equivalent(in, path, ec))
      throw UsageError(flag + " " + path + " is an input (" + in + "): refusing to overwrite it");
}

}  // namespace yelan::cli
