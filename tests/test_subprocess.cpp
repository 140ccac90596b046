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

namespace {
struct ScratchDir {  // removed even when a REQUIRE fails
  std::filesystem::path p = std::filesystem::temp_directory_path() / ("yelan-subprocess-" + std::to_string(::getpid()));
  ScratchDir() { std::filesystem::create_directories(p / "it's here"); }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(p, ec);
  }
};
}  // namespace

TEST_CASE("subprocess: exit codes, stdin from a file, the working directory, and a program that is not there", "[engine][subprocess]") {
  ScratchDir scratch;
  const auto& dir = scratch.p;
  std::ofstream(dir / "in.txt") << "three\nlines\nhere\n";

  Program code{{"sh", "-c", "exit 3"}};
  auto r = run_program(code);
  CHECK(r.started);
  CHECK(r.exit_code == 3);
  CHECK_FALSE(r.ok());
  CHECK(r.why() == "exit code 3");

  Program killed{{"sh", "-c", "kill -9 $$"}};
  r = run_program(killed);
  CHECK(r.started);
  CHECK(r.exit_code == -1);
  CHECK_FALSE(r.ok());
  CHECK_THAT(r.why(), Catch::StartsWith("killed by signal 9"));

  Program big{{"head", "-c", "1000000", "/dev/zero"}};  // far more than a pipe holds
  big.capture_stdout = true;
  r = run_program(big);
  REQUIRE(r.ok());
  CHECK(r.out == std::string(1000000, '\0'));

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
    CHECK_FALSE(r.why().empty());
  }

  // A working directory or stdin that cannot be opened: not started, and the reason says which.
  Program nowhere{{"pwd"}};
  nowhere.cwd = (dir / "missing").string();
  r = run_program(nowhere);
  CHECK_FALSE(r.started);
  CHECK_THAT(r.why(), Catch::Contains("in " + nowhere.cwd) && Catch::Contains("No such file"));
  Program no_input{{"wc", "-l"}};
  no_input.stdin_path = (dir / "missing.txt").string();
  r = run_program(no_input);
  CHECK_FALSE(r.started);
  CHECK_THAT(r.why(), Catch::Contains("stdin " + no_input.stdin_path));

  // A relative program path is found from the caller's directory even with a cwd for the child.
  std::ofstream(dir / "hello.sh") << "#!/bin/sh\necho hello\n";
  std::filesystem::permissions(dir / "hello.sh", std::filesystem::perms::owner_all);
  const auto here = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  Program rel{{"./hello.sh"}};
  rel.cwd = (dir / "it's here").string();
  rel.capture_stdout = true;
  r = run_program(rel);
  std::filesystem::current_path(here);
  REQUIRE(r.ok());
  CHECK(r.out == "hello\n");
}

TEST_CASE("subprocess: on_path finds executables on PATH and by path, and nothing else", "[engine][subprocess]") {
  CHECK(yelan::on_path("sh"));
  CHECK(yelan::on_path("/bin/sh"));
  CHECK_FALSE(yelan::on_path("yelan-no-such-program"));
  CHECK_FALSE(yelan::on_path("/etc/passwd"));  // there, but not executable
  CHECK_FALSE(yelan::on_path("/bin"));         // a directory
  CHECK_FALSE(yelan::on_path(""));
}
