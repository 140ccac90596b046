// Recordings a command is about to read, vetted before it allocates its networks.
#pragma once
#include <ostream>
#include <string>
#include <vector>

namespace yelan::cli {

// camera::sim::vet_recordings at the engine's thread count, with a line on `err` when any
// file had not been vetted before (on a new machine that is every file: minutes). Throws the
// first FormatError (exit 2, naming the file) before any work.
void vet_recordings_up_front(const std::vector<std::string>& recordings, std::ostream& err);

}  // namespace yelan::cli
