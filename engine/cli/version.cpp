#include <H5public.h>
#include <libusb.h>
#include <omp.h>

#include <Eigen/Core>
#include <cstdlib>
#include <sstream>

#include "engine/cli/cli.h"
#include "engine/threads.h"
#include "kernels/cpu.h"

#ifndef YELAN_VERSION
#define YELAN_VERSION "unknown"
#endif
#ifndef YELAN_BUILD_TYPE
#define YELAN_BUILD_TYPE "unknown"
#endif

namespace yelan::cli {

std::string version_text() {
  std::ostringstream s;
  const char* forced = std::getenv("YELAN_ISA");
  s << "yelan " << YELAN_VERSION << "\n";
  s << "isa: " << kernels::isa_name(kernels::active_isa())
    << (forced && *forced ? " (forced by YELAN_ISA)" : "")
    << "; best here: " << kernels::isa_name(kernels::best_isa())
    << "; available: " << kernels::supported_isas() << "\n";
  s << "cpu features: " << kernels::cpu_features().describe() << "\n";
  s << "threads: " << threads() << "\n";
  unsigned maj = 0, min = 0, rel = 0;
  H5get_libversion(&maj, &min, &rel);
  const libusb_version* usb = libusb_get_version();
  s << "libraries: HDF5 " << maj << "." << min << "." << rel << ", libusb " << usb->major << "."
    << usb->minor << "." << usb->micro << ", Eigen " << EIGEN_WORLD_VERSION << "."
    << EIGEN_MAJOR_VERSION << "." << EIGEN_MINOR_VERSION << ", OpenMP " << _OPENMP << "\n";
  s << "build: " << YELAN_BUILD_TYPE << ", " << __VERSION__ << "\n";
  return s.str();
}

}  // namespace yelan::cli
