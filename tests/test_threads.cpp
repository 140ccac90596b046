#include <catch2/catch.hpp>

#include <cstdlib>
#include <stdexcept>

#include "engine/threads.h"

TEST_CASE("thread counts parse strictly", "[engine][threads]") {
  CHECK(yelan::parse_thread_count("1") == 1);
  CHECK(yelan::parse_thread_count("2") == 2);
  CHECK(yelan::parse_thread_count("1024") == 1024);
  for (const char* bad : {"", "0", "-1", "1025", "2x", " 2", "two", "1.5"}) {
    INFO("'" << bad << "'");
    CHECK_FALSE(yelan::parse_thread_count(bad));
  }
}

TEST_CASE("set_threads and YELAN_THREADS control the OpenMP team", "[engine][threads]") {
  const int saved = yelan::threads();
  yelan::set_threads(1);
  CHECK(yelan::threads() == 1);
  yelan::set_threads(3);
  CHECK(yelan::threads() == 3);
  CHECK_THROWS_AS(yelan::set_threads(0), std::invalid_argument);

  ::setenv("YELAN_THREADS", "2", 1);
  yelan::init_threads_from_env();
  CHECK(yelan::threads() == 2);
  ::setenv("YELAN_THREADS", "lots", 1);
  CHECK_THROWS_AS(yelan::init_threads_from_env(), std::invalid_argument);
  CHECK(yelan::threads() == 2);
  ::unsetenv("YELAN_THREADS");
  yelan::set_threads(saved);
}
