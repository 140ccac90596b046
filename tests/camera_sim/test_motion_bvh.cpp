// BVH reader: the real CMU files against their README figures, FK against hand-computed
// transforms, and bad input (named errors, truncated and garbled copies) never crashing.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "camera/sim/bvh.h"
#include "camera/sim/rng.h"
#include "test_util.h"

using namespace yelan::camera::sim;
namespace fs = std::filesystem;

namespace {

struct TempBvh {
  fs::path path;
  TempBvh(const std::string& name, const std::string& text)
      : path(fs::temp_directory_path() / ("yelan_motion_" + name + "_" + std::to_string(::getpid()) + ".bvh")) {
    std::ofstream(path, std::ios::binary) << text;
  }
  ~TempBvh() {
    std::error_code ec;
    fs::remove(path, ec);
  }
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A root with position + ZXY rotation, a child with position channels and XZ rotation, an
// End Site. Two frames.
const char* kSmall =
    "HIERARCHY\n"
    "ROOT Root\n"
    "{\n"
    "  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Arm\n"
    "  {\n"
    "    OFFSET 1 0 0\n"
    "    CHANNELS 5 Xposition Yposition Zposition Xrotation Zrotation\n"
    "    End Site\n"
    "    {\n"
    "      OFFSET 2 0 0\n"
    "    }\n"
    "  }\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time: 0.01\n"
    "1 2 3 90 0 0 0 0 0 0 0\n"
    "1 2 3 0 0 0 0.5 0 0 90 90\n";

}  // namespace

TEST_CASE("motion bvh reads every CMU file as its README states") {
  struct Row {
    const char* file;
    int frames;
    double first[3];  // root position of frame 1 (the T-pose)
    double last0;     // first value of the last frame
  };
  const Row rows[] = {{"02_01", 344, {0, 0, 0}, 11.0237},   {"02_03", 174, {0, 0, 0}, 9.0701},
                      {"05_04", 1200, {0, 0, 0}, -3.5917},  {"05_07", 1192, {0, 0, 0}, 8.5510},
                      {"05_14", 643, {0, 0, 0}, -1.5824},   {"05_16", 526, {0.637, 16.3739, 34.5317}, -2.4995},
                      {"05_19", 861, {0, 0, 0}, -0.1370},   {"93_03", 443, {0, 0, 0}, -14.2550}};
  for (const Row& r : rows) {
    INFO(r.file);
    const BvhClip c = read_bvh(yelan::test::shared_data_or_skip(std::string("mocap/") + r.file + ".bvh"));
    CHECK(c.frame_count == r.frames);
    CHECK(c.values.size() == std::size_t(r.frames) * 96);
    CHECK(c.channel_count == 96);
    CHECK(c.joints.size() == 31 + 7);
    int end_sites = 0;
    for (const auto& j : c.joints) end_sites += j.end_site;
    CHECK(end_sites == 7);
    CHECK(c.frame_time_s == Approx(0.0083333).epsilon(1e-12));
    CHECK(c.joints[0].name == "Hips");
    CHECK(c.joints[0].parent == -1);
    REQUIRE(c.joints[0].channels.size() == 6);
    CHECK(c.joints[0].channels[0] == BvhChannel::Xposition);
    CHECK(c.joints[0].channels[3] == BvhChannel::Zrotation);
    CHECK(c.joints[0].channels[5] == BvhChannel::Xrotation);
    CHECK(c.joints[c.find("LeftUpLeg")].parent == c.find("LHipJoint"));
    CHECK(c.joints[c.find("LeftToeBase") + 1].end_site);
    CHECK(c.frame(c.frame_count - 1)[0] == Approx(r.last0).margin(1e-9));
    if (r.first[1] != 0) {
      CHECK(c.frame(0)[1] == Approx(r.first[1]).margin(1e-9));
      CHECK(c.frame(0)[9] == Approx(-21).margin(1e-9));  // T-pose's LHipJoint... LeftUpLeg Z rotation
      CHECK(c.frame(1)[3] == Approx(-179.1270).margin(1e-9));
    }
  }
  // 05_16 LeftUpLeg offset, verbatim from the file.
  const BvhClip c = read_bvh(yelan::test::shared_data_or_skip("mocap/05_16.bvh"));
  const auto& o = c.joints[c.find("LeftUpLeg")].offset;
  CHECK(o.x() == Approx(1.64549));
  CHECK(o.y() == Approx(-1.70879));
  CHECK(o.z() == Approx(0.84566));
}

TEST_CASE("motion bvh forward kinematics matches hand-computed transforms") {
  TempBvh f("small", kSmall);
  const BvhClip c = read_bvh(f.path.string());
  REQUIRE(c.joints.size() == 3);
  CHECK(c.channel_count == 11);
  CHECK(c.joints[1].first_channel == 6);
  CHECK(c.joints[2].end_site);
  std::vector<Eigen::Vector3d> p;
  std::vector<Eigen::Quaterniond> q;
  // Frame 0: root at (1,2,3) turned 90 deg about Z: the arm (1,0,0) goes to +Y.
  bvh_frame_pose(c, 0, p, q);
  CHECK((p[0] - Eigen::Vector3d(1, 2, 3)).norm() < 1e-12);
  CHECK((p[1] - Eigen::Vector3d(1, 3, 3)).norm() < 1e-12);
  CHECK((p[2] - Eigen::Vector3d(1, 5, 3)).norm() < 1e-12);
  // Frame 1: arm translated by its position channels (0.5,0,0) on top of its offset, then
  // X 90 then Z 90 in file order: R = Rx(90) Rz(90), so the End Site (2,0,0) goes
  // Rz: (0,2,0), Rx: (0,0,2). The other order would leave it on +Y.
  bvh_frame_pose(c, 1, p, q);
  CHECK((p[1] - Eigen::Vector3d(2.5, 2, 3)).norm() < 1e-12);
  CHECK((p[2] - Eigen::Vector3d(2.5, 2, 5)).norm() < 1e-12);
  const auto rest = bvh_rest_positions(c);
  CHECK((rest[2] - Eigen::Vector3d(3, 0, 0)).norm() < 1e-12);
}

TEST_CASE("motion bvh errors name the file, the line and what was expected") {
  struct Bad {
    const char* name;
    std::string text;
    long line;
    const char* says;
  };
  const std::string hier =
      "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n}\n";
  const std::vector<Bad> bad = {
      {"channels", hier + "MOTION\nFrames: 2\nFrame Time: 0.01\n1 2 3\n1 2\n", 11, "expected 3 values, found 2"},
      {"toomany", hier + "MOTION\nFrames: 1\nFrame Time: 0.01\n1 2 3 4\n", 10, "more than the 3 values"},
      {"number", hier + "MOTION\nFrames: 1\nFrame Time: 0.01\n1 2x 3\n", 10, "expected a number, found '2x'"},
      {"noframes", hier + "MOTION\nFrame Time: 0.01\n1 2 3\n", 8, "expected 'Frames: N'"},
      {"truncated", hier + "MOTION\nFrames: 3\nFrame Time: 0.01\n1 2 3\n", 10, "truncated: 'Frames: 3' but 1"},
      {"absurd", hier + "MOTION\nFrames: 1\nFrame Time: 0.01\n1 1e300 3\n", 10, "absurd value 1e300"},
      {"absurdframes", hier + "MOTION\nFrames: 99999999999\nFrame Time: 0.01\n", 8, "absurd frame count"},
      {"frametime", hier + "MOTION\nFrames: 1\nFrame Time: -1\n1 2 3\n", 9, "frame time in (0, 10]"},
      {"extra", hier + "MOTION\nFrames: 1\nFrame Time: 0.01\n1 2 3\n4 5 6\n", 11, "more frame lines"},
      {"nan", hier + "MOTION\nFrames: 1\nFrame Time: 0.01\n1 nan 3\n", 10, "expected a number"},
      {"unclosed", "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 1 Xposition\n", 5, "unexpected end of file"},
      {"extra_brace", hier + "}\nMOTION\n", 7, "expected 'MOTION', found '}'"},
      {"missing_brace", "HIERARCHY\nROOT A\n OFFSET 0 0 0\n}\n", 3, "expected '{', found 'OFFSET'"},
      {"channel", "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 1 Wrotation\n}\n", 5, "expected a channel name"},
      {"count", "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 9 Xposition\n}\n", 5, "channel count 0..6"},
      {"offset", "HIERARCHY\nROOT A\n{\n OFFSET 0 zero 0\n}\n", 4, "expected OFFSET coordinate"},
      {"nooffset", "HIERARCHY\nROOT A\n{\n CHANNELS 1 Xposition\n}\nMOTION\n", 5, "has no OFFSET"},
      {"keyword", "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n BONE B\n}\n", 5, "found 'BONE'"},
      {"notbvh", "PK\x03\x04 zip", 1, "expected 'HIERARCHY'"},
      {"empty", "", 1, "unexpected end of file"},
      {"twice", "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 2 Xrotation Xrotation\n}\n", 5, "twice"},
      {"tworoots", hier + "ROOT B\n", 7, "a second ROOT"},
  };
  for (const Bad& b : bad) {
    INFO(b.name);
    TempBvh f(b.name, b.text);
    try {
      read_bvh(f.path.string());
      FAIL("no exception");
    } catch (const BvhError& e) {
      const std::string what = e.what();
      INFO(what);
      CHECK(what.find(f.path.string()) == 0);
      CHECK(what.find("line " + std::to_string(b.line) + ":") != std::string::npos);
      CHECK(what.find(b.says) != std::string::npos);
      CHECK(e.line() == b.line);
    }
  }
  CHECK_THROWS_AS(read_bvh("/nonexistent/yelan.bvh"), BvhError);
}

TEST_CASE("motion bvh truncated and garbled copies of a real file fail cleanly") {
  const std::string good = slurp(yelan::test::shared_data_or_skip("mocap/02_03.bvh"));
  REQUIRE(good.size() == 134655);
  const std::size_t hier_end = good.find("MOTION");
  int ok = 0, errors = 0;
  // Cuts: dense through the hierarchy, then spread over the motion data.
  std::vector<std::size_t> cuts;
  for (std::size_t k = 0; k < hier_end; k += 97) cuts.push_back(k);
  for (int k = 0; k < 40; ++k) cuts.push_back(hier_end + std::size_t(uniform01(7, 1, k) * (good.size() - hier_end)));
  for (std::size_t cut : cuts) {
    TempBvh f("cut", good.substr(0, cut));
    try {
      read_bvh(f.path.string());
      ++ok;
    } catch (const BvhError&) {
      ++errors;
    }
  }
  // A cut that happens to fall at a line end after the last frame could parse; none other.
  CHECK(ok == 0);
  CHECK(errors == int(cuts.size()));
  // Garbled: a few random bytes overwritten with random characters, most of them legal BVH.
  const char alphabet[] = "{}0123456789.-+eE \n\tXYZabcOFFSETCHANNELSJOINTEnd Site\0\xff";
  int garbled_ok = 0, garbled_err = 0;
  for (int k = 0; k < 120; ++k) {
    std::string s = good;
    const int n = 1 + int(uniform01(11, 2, k) * 4);
    for (int i = 0; i < n; ++i) {
      const std::size_t at = k % 2 ? std::size_t(uniform01(11, 3, k * 8 + i) * hier_end)
                                   : std::size_t(uniform01(11, 3, k * 8 + i) * s.size());
      s[at] = alphabet[std::size_t(uniform01(11, 4, k * 8 + i) * (sizeof(alphabet) - 1))];
    }
    TempBvh f("garbled", s);
    try {
      const BvhClip c = read_bvh(f.path.string());
      CHECK(c.values.size() == std::size_t(c.frame_count) * c.channel_count);
      ++garbled_ok;
    } catch (const BvhError& e) {
      CHECK(std::string(e.what()).find("line ") != std::string::npos);
      ++garbled_err;
    }
  }
  CHECK(garbled_ok + garbled_err == 120);
  CHECK(garbled_err > 30);  // most garbling must be caught
}
