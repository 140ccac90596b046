// HDF5 files we did not write are read first in a child process (camera/io/untrusted.h):
// libhdf5 1.10.8 crashes on crafted files, and that must become an error naming the file.
#include <catch2/catch.hpp>

#include <signal.h>

#include <atomic>
#include <cstdlib>
#include <vector>

#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "camera/io/format_error.h"
#include "camera/io/untrusted.h"
#include "io_test_util.h"

using namespace yelan;

TEST_CASE("vetting in a child: a crash is an error naming the file, an ordinary error is left to the real read",
          "[io][h5][untrusted]") {
  test::ScratchDir d("untrusted");
  const auto touch = [&](const std::string& name) {
    test::write_text(d.file(name), name);
    return d.file(name);
  };
  const std::string crash = touch("crash.h5");
  try {
    camera::vet_in_child(crash, [] { ::raise(SIGSEGV); });
    FAIL("a crash in the child was not reported");
  } catch (const camera::FormatError& e) {
    CHECK(e.file() == crash);
    CHECK_THAT(e.problem(), Catch::Contains("libhdf5 crashed reading it"));
  }
  // An exception in the child: the parent's own read will report it, with its own words.
  CHECK_NOTHROW(camera::vet_in_child(touch("error.h5"), [] { throw std::runtime_error("ordinary"); }));
  // Too slow: the CPU limit.
  camera::UntrustedLimits quick;
  quick.seconds = 1;
  CHECK_THROWS_WITH(camera::vet_in_child(touch("slow.h5"), [] {
                      std::atomic<unsigned long> i{0};
                      for (;;) i.fetch_add(1, std::memory_order_relaxed);
                    }, quick),
                    Catch::Contains("more than 1 s of CPU"));
  // A file that passed once is not read again (a trainer reopens its recordings all the time).
  const std::string good = touch("good.h5");
  CHECK_NOTHROW(camera::vet_in_child(good, [] {}));
  CHECK_NOTHROW(camera::vet_in_child(good, [] { ::raise(SIGSEGV); }));
  // ... unless it changed.
  test::write_text(good, "changed, and longer");
  CHECK_THROWS_AS(camera::vet_in_child(good, [] { ::raise(SIGSEGV); }), camera::FormatError);
}

TEST_CASE("every byte of an event HDF5 file's head, zeroed or bit-flipped: an error or events, never a crash",
          "[io][h5][untrusted]") {
  test::ScratchDir d("untrusted-sweep");
  const std::string clean = d.file("clean.h5");
  {
    camera::StreamInfo info;
    info.width = 346, info.height = 260;
    auto w = camera::open_event_writer(clean, info);
    std::vector<camera::Event> ev;
    for (int i = 0; i < 3000; ++i) ev.push_back({std::int64_t(i) * 37, std::uint16_t(i % 346), std::uint16_t(i % 260), std::uint8_t(i & 1)});
    w->write(ev);
    w->close();
  }
  const std::vector<unsigned char> bytes = test::read_bytes(clean);
  REQUIRE(bytes.size() > 4096);
  int refused = 0, read = 0;
  // Every 3rd byte of the superblock and the metadata after it (where the crashes were found),
  // two mutations each (every byte with YELAN_SLOW_TESTS set).
  const int step = std::getenv("YELAN_SLOW_TESTS") ? 1 : 3;
  for (std::size_t at = 0; at < 4096; at += std::size_t(step)) {
    for (const unsigned char flip : {0x00, 0x08}) {
      std::vector<unsigned char> b = bytes;
      b[at] = flip == 0 ? 0 : (b[at] ^ flip);
      if (b == bytes) continue;
      std::string name = std::to_string(at);  // appended: GCC 12 warns falsely on "m" + ... (-Wrestrict)
      name += '-';
      name += std::to_string(int(flip));
      name += ".h5";
      const std::string path = d.file(name);
      test::write_bytes(path, b);
      try {
        auto r = camera::open_event_file(path);
        std::vector<camera::Event> ev;
        while (r->read(ev, 1 << 16)) ev.clear();
        ++read;
      } catch (const std::exception&) {
        ++refused;
      }
      std::filesystem::remove(path);
    }
  }
  INFO(refused << " refused, " << read << " read");
  CHECK(refused > 0);
  CHECK(refused + read > 1000);
}
