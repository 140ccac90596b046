// The one temp-file helper: exclusive creation that never follows a planted link, commit by
// rename, removal when abandoned, and removal of live temporary files on SIGINT / SIGTERM.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "camera/io/temp_file.h"
#include "io_test_util.h"

using yelan::camera::TempFile;
using namespace yelan::test;

namespace {
std::string read_text(const std::string& path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), {});
}
int temps_in(const std::string& dir) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.path().filename().string().find(".tmp-") != std::string::npos;
  return n;
}
}  // namespace

TEST_CASE("TempFile: exclusive, never through a planted link; committed by rename, else removed", "[io][atomic]") {
  ScratchDir dir("tempfile");
  const std::string out = dir.file("out.txt"), victim = dir.file("victim.txt");
  write_text(victim, "precious");
  // Links planted at every name the old scheme would have used: out.txt.tmp-PID.
  std::filesystem::create_symlink(victim, out + ".tmp-" + std::to_string(::getpid()));
  {
    TempFile t(out);
    CHECK(t.path() != out + ".tmp-" + std::to_string(::getpid()));
    CHECK_FALSE(std::filesystem::is_symlink(t.path()));
    std::ofstream(t.path()) << "new";
    t.commit();
  }
  CHECK(read_text(out) == "new");
  CHECK(read_text(victim) == "precious");
  struct stat st {};
  REQUIRE(::stat(out.c_str(), &st) == 0);
  const mode_t mask = ::umask(0);
  ::umask(mask);
  CHECK((st.st_mode & 0777) == (0666 & ~mask));  // an ordinary file's permissions, not mkstemp's 0600
  {
    TempFile abandoned(dir.file("never.txt"));
    std::ofstream(abandoned.path()) << "half";
  }
  CHECK_FALSE(std::filesystem::exists(dir.file("never.txt")));
  CHECK(temps_in(dir.dir.string()) == 1);  // only the planted link is left
  CHECK_THROWS_WITH(TempFile(dir.file("no/such/dir/x.txt")), Catch::Contains("cannot create a temporary file beside"));
  yelan::camera::write_file_atomically(dir.file("t.json"), "{}\n");
  CHECK(read_text(dir.file("t.json")) == "{}\n");
}

TEST_CASE("TempFile: SIGINT and SIGTERM remove the live temporary files, and the process dies by the signal", "[io][atomic]") {
  ScratchDir dir("tempsignal");
  for (const int sig : {SIGINT, SIGTERM}) {
    int ready[2];
    REQUIRE(::pipe(ready) == 0);
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      ::close(ready[0]);
      yelan::camera::remove_temp_files_on_signal();
      TempFile a(dir.file("a.bin")), b(dir.file("b.bin"));
      char c = 1;
      if (::write(ready[1], &c, 1) != 1) ::_exit(3);
      for (;;) ::pause();
    }
    ::close(ready[1]);
    char c = 0;
    REQUIRE(::read(ready[0], &c, 1) == 1);
    ::close(ready[0]);
    CHECK(temps_in(dir.dir.string()) == 2);
    ::kill(child, sig);
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    CHECK(WIFSIGNALED(status));
    CHECK(WTERMSIG(status) == sig);
    CHECK(temps_in(dir.dir.string()) == 0);
  }
}
