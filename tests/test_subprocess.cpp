#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "engine/subprocess.h"

using yelan::Program;
using yelan::run_program;

TEST_CASE("subprocess: arguments reach the program as they are, with no shell to quote for", "[engine][subprocess]") {
  Program p;
  p.argv = {"printf", "%s|", "it's", "a b", "$HOME", "x; exit 7", "*"};
  p.capture_stdout = true;
  const auto r = run_program(p);
  REQUIRE(r.ok());
  CHECK(r.out == "it's|a b|$HOME|x; exit 7|*|");
}

TEST_CASE("subprocess: exit codes, stdin from a file, the working directory, and a program that is not there", "[engine][subprocess]") {
  const auto dir = std::filesystem::temp_directory_path() / ("yelan-subprocess-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "it's here");
  std::ofstream(dir / "in.txt") << "three\nlines\nhere\n";

  Program code{{"sh", "-c", "exit 3"}};
  auto r = run_program(code);
  CHECK(r.started);
  CHECK(r.exit_code == 3);
  CHECK_FALSE(r.ok());

  Program wc{{"wc", "-l"}};
  wc.stdin_path = (dir / "in.txt").string();
  wc.capture_stdout = true;
  r = run_program(wc);
  REQUIRE(r.ok());
  CHECK(std::stoi(r.out) == 3);

  wc.stdin_path = "/dev/null";  // the default: a program never waits on the terminal
  r = run_program(wc);
  REQUIRE(r.ok());
  CHECK(std::stoi(r.out) == 0);

  Program pwd{{"pwd"}};
  pwd.cwd = (dir / "it's here").string();
  pwd.capture_stdout = true;
  r = run_program(pwd);
  REQUIRE(r.ok());
  CHECK(std::filesystem::equivalent(r.out.substr(0, r.out.find('\n')), dir / "it's here"));

  for (const std::vector<std::string>& argv : std::vector<std::vector<std::string>>{
           {"yelan-no-such-program"}, {(dir / "in.txt").string()}, {"/nonexistent/bin/x"}, {}}) {
    Program none{argv};
    r = run_program(none);
    CHECK_FALSE(r.started);
    CHECK_FALSE(r.ok());
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("subprocess: on_path finds executables on PATH and by path, and nothing else", "[engine][subprocess]") {
  CHECK(yelan::on_path("sh"));
  CHECK(yelan::on_path("/bin/sh"));
  CHECK_FALSE(yelan::on_path("yelan-no-such-program"));
  CHECK_FALSE(yelan::on_path("/etc/passwd"));  // there, but not executable
  CHECK_FALSE(yelan::on_path("/bin"));         // a directory
  CHECK_FALSE(yelan::on_path(""));
}
