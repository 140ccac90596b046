#include "engine/cli/vet_recordings.h"

#include <chrono>
#include <iomanip>
#include <sstream>

#include "camera/sim/recording_reader.h"
#include "engine/threads.h"

namespace yelan::cli {

void vet_recordings_up_front(const std::vector<std::string>& recordings, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = camera::sim::vet_recordings(recordings, threads());
  if (!n) return;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;  // the caller's stream keeps its own number format
  line << "vetted " << n << " of " << recordings.size() << " recordings (read whole in a child first; camera/io/untrusted.h) in "
       << std::fixed << std::setprecision(1) << s << " s\n";
  err << line.str();
}

}  // namespace yelan::cli
