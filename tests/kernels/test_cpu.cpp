#include <catch2/catch.hpp>

#include <cstdlib>
#include <stdexcept>

#include "kernels/cpu.h"
#include "kernels/eltwise.h"
#include "test_util.h"

using namespace yelan::kernels;

TEST_CASE("ISA names parse and print as the same words", "[cpu]") {
  for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512, Isa::neon}) {
    auto parsed = parse_isa(isa_name(isa));
    REQUIRE(parsed);
    CHECK(*parsed == isa);
  }
  CHECK_FALSE(parse_isa(""));
  CHECK_FALSE(parse_isa("AVX2"));
  CHECK_FALSE(parse_isa("avx512 "));
  CHECK_FALSE(parse_isa("sse"));
}

TEST_CASE("scalar always runs and the best ISA is one this CPU supports", "[cpu]") {
  CHECK(isa_supported(Isa::scalar));
  CHECK(isa_supported(best_isa()));
  CHECK(supported_isas().find(isa_name(best_isa())) != std::string::npos);
#if defined(__x86_64__)
  CHECK_FALSE(isa_supported(Isa::neon));
  CHECK(isa_supported(Isa::avx2) == (cpu_features().avx2 && cpu_features().fma));
  CHECK(isa_supported(Isa::avx512) == (cpu_features().avx512f && cpu_features().avx512bw &&
                                       cpu_features().avx512vl && cpu_features().avx512dq &&
                                       cpu_features().fma));
  if (cpu_features().avx512f) CHECK(best_isa() == Isa::avx512);
#elif defined(__aarch64__)
  CHECK(cpu_features().neon);  // ASIMD is mandatory on aarch64 Linux
  CHECK(best_isa() == Isa::neon);
  CHECK_FALSE(isa_supported(Isa::avx2));
#endif
}

TEST_CASE("feature description lists exactly the detected features", "[cpu]") {
  const CpuFeatures& f = cpu_features();
  std::string d = " ";  // built in steps: GCC 12 -Wrestrict misfires on " " + s + " "
  d += f.describe();
  d += " ";
  CHECK((d.find(" avx2 ") != std::string::npos) == f.avx2);
  CHECK((d.find(" avx512f ") != std::string::npos) == f.avx512f);
  CHECK((d.find(" neon ") != std::string::npos) == f.neon);
}

TEST_CASE("forcing each supported ISA switches every kernel table to it", "[cpu]") {
  yelan::test::IsaGuard guard;
  for (Isa isa : yelan::test::supported_isas()) {
    INFO("isa " << isa_name(isa));
    set_isa(isa);
    CHECK(active_isa() == isa);
    CHECK(eltwise_kernels().isa == isa);
  }
}

TEST_CASE("forcing an ISA the CPU lacks throws and changes nothing", "[cpu]") {
  yelan::test::IsaGuard guard;
  const Isa before = active_isa();
#if defined(__aarch64__)
  CHECK_THROWS_AS(set_isa(Isa::avx512), std::invalid_argument);
#else
  CHECK_THROWS_AS(set_isa(Isa::neon), std::invalid_argument);
#endif
  CHECK(active_isa() == before);
}

// ctest runs this binary once per ISA with YELAN_ISA set (see tests/CMakeLists.txt).
TEST_CASE("YELAN_ISA decides the active ISA at start-up", "[cpu][forced-isa]") {
  const char* env = std::getenv("YELAN_ISA");
  if (!env || !*env) {
    CHECK(active_isa() == best_isa());
    return;
  }
  auto isa = parse_isa(env);
  REQUIRE(isa);
  CHECK(active_isa() == *isa);
  CHECK(eltwise_kernels().isa == *isa);
}
