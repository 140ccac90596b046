// Shared test main. If YELAN_ISA forces an ISA this CPU cannot run, the whole binary is
// reported as skipped (exit 77, ctest's SKIP_RETURN_CODE), not as passed or failed.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <stdlib.h>

#include "kernels/cpu.h"

int main(int argc, char** argv) {
  // Tests (and the yelan processes they start) keep out of the user's cache of vetted files
  // (camera/io/untrusted.h); the test of that cache names its own.
  ::setenv("YELAN_VET_CACHE", "off", 0);
  if (const char* env = std::getenv("YELAN_ISA"); env && *env) {
    auto isa = yelan::kernels::parse_isa(env);
    if (isa && !yelan::kernels::isa_supported(*isa)) {
      std::printf("SKIP: YELAN_ISA=%s is not supported on this CPU (available: %s)\n", env,
                  yelan::kernels::supported_isas().c_str());
      return 77;
    }
  }
  return Catch::Session().run(argc, argv);
}
