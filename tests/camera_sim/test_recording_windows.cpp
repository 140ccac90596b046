// Windows read from labelled recordings on disk: frames on the mask times, the TORE of
// exactly the events since the warm-up, joints and masks of the file, seeded picks that
// depend on the window number alone, and clear errors on files that are not recordings.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "camera/io/format_error.h"
#include "camera/io/h5.h"
#include "camera/io/untrusted.h"
#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"

using namespace yelan::camera;
using namespace yelan::camera::sim;

namespace {

struct Dir {
  std::filesystem::path p;
  Dir() : p(std::filesystem::temp_directory_path() / ("yelan-recwin-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(p);
    std::filesystem::create_directories(p);
  }
  ~Dir() { std::filesystem::remove_all(p); }
  std::string operator/(const std::string& f) const { return (p / f).string(); }
};

std::string record(const Dir& d, const std::string& preset, double seconds) {
  SimSpec s = preset_spec(preset);
  s.duration_s = seconds;
  s.seed = 5;
  const std::string path = d / (preset + ".yelan.h5");
  write_recording(s, path);
  return path;
}

// Replaces dataset `name` of the recording with a chunked one of `dims` none of whose chunks is
// written: a claim of any size at no cost on disk, as a corrupt file can make it.
void claim_unwritten(const std::string& path, const char* name, hid_t type, const std::vector<hsize_t>& dims,
                     const std::vector<hsize_t>& chunk) {
  {
    h5::H5Id f = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open");
    h5::check(H5Ldelete(f.get(), name, H5P_DEFAULT), "delete");
    h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "space");
    h5::H5Id props = h5::check(H5Pcreate(H5P_DATASET_CREATE), "props");
    h5::check(H5Pset_chunk(props.get(), int(chunk.size()), chunk.data()), "chunk");
    h5::check(H5Dcreate2(f.get(), name, type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), "create");
  }
  forget_vetted_files();
}

}  // namespace

TEST_CASE("recording windows: frames on the mask times, TORE of the events since the warm-up, the file's joints and masks", "[sim]") {
  Dir d;
  const std::string path = record(d, "ben-dance3-front-high-static", 0.5);
  const RecordingInfo info = read_recording_info(path);
  CHECK(info.name == "ben-dance3-front-high-static");
  CHECK(info.character == "ben");
  CHECK(info.view == "front");
  CHECK(info.camera.width == 346);
  WindowStreamOptions o;
  o.window = 3;
  o.warmup_s = 0.1;
  o.counts = true;
  auto reader = open_event_file(path);
  std::vector<Event> ev;
  while (reader->read(ev, 1 << 16) > 0) {
  }
  REQUIRE(!ev.empty());
  // The first frame: the first mask time with 0.1 s of events before it.
  std::size_t first = 0;
  while (info.mask_t[first] - 100000 < ev.front().t) ++first;
  RecordingWindowStream stream({path}, 1, o);
  CHECK(stream.windows_in(0) == int(info.mask_t.size() - first) / 3);
  SimWindow a, b;
  stream.next(a);
  stream.next(b);
  REQUIRE(a.frames.size() == 3);
  CHECK(a.scene == info.name);
  CHECK(a.frames[0].t_us == info.mask_t[first]);
  CHECK(a.frames[1].t_us - a.frames[0].t_us == 20000);
  CHECK(b.frames[0].t_us - a.frames[2].t_us == 20000);  // consecutive windows follow on
  // The TORE and counts by hand: every event from the warm-up's start up to the frame time.
  const std::int64_t t0 = a.frames[0].t_us - 100000;
  for (const SimFrame* f : {&a.frames[0], &a.frames[2], &b.frames[1]}) {
    ToreVolume tore(346, 260, o.tore);
    double counted = 0;
    for (const Event& e : ev)
      if (e.t >= t0 && e.t <= f->t_us) {
        tore.update(e);
        counted += e.t > f->t_us - 20000;
      }
    std::vector<float> want(tore.volume_size());
    tore.readout(f->t_us, want.data());
    CHECK(f->tore == want);
    double sum = 0;
    for (float c : f->counts) sum += c;
    CHECK(sum == counted);
    // Labels are at 300 Hz, so a frame time is a label time: its joints exactly.
    const auto it = std::find(info.label_t.begin(), info.label_t.end(), f->t_us);
    REQUIRE(it != info.label_t.end());
    const std::size_t row = std::size_t(it - info.label_t.begin());
    CHECK(f->joints_mm[7][2] == Approx(info.joints[(row * 13 + 7) * 3 + 2]));
    CHECK(f->mask.size() == std::size_t(346 * 260));
  }
  std::size_t human = 0;
  for (auto m : a.frames[0].mask) human += m;
  CHECK(human > 100);  // the dancer is in the mask
}

TEST_CASE("recording windows: a seeded window depends on its number alone, and splits are by recording", "[sim]") {
  Dir d;
  const std::vector<std::string> paths = {record(d, "ben-dance3-front-high-static", 0.4),
                                          record(d, "ana-05_04-left-medium-dynamic", 0.4)};
  WindowStreamOptions o;
  o.window = 2;
  o.shuffle = true;
  RecordingWindowStream s1(paths, 9, o), s2(paths, 9, o);
  SimWindow w;
  for (int k = 0; k < 4; ++k) s1.next(w);
  SimWindow fifth, again;
  s1.next(fifth);
  s2.seek_window(4);
  s2.next(again);
  CHECK(fifth.scene == again.scene);
  CHECK(fifth.frames[1].t_us == again.frames[1].t_us);
  CHECK(fifth.frames[1].tore == again.frames[1].tore);
  // Every tenth recording validates; never a recording on both sides.
  std::vector<std::string> all, train, val;
  for (int i = 0; i < 23; ++i) all.push_back(std::to_string(100 + i));
  split_by_recording(all, train, val);
  CHECK(val == std::vector<std::string>{"109", "119"});
  CHECK(train.size() == 21);
  split_by_recording({"a", "b"}, train, val);
  CHECK(val == std::vector<std::string>{"b"});
  CHECK_THROWS(split_by_recording({"a"}, train, val));
}

TEST_CASE("recording windows: files that are not labelled recordings are named with what is missing", "[sim]") {
  Dir d;
  CHECK_THROWS_WITH(list_recordings(d / ""), Catch::Contains("no recordings"));
  CHECK_THROWS_WITH(list_recordings(d / "nothing-here"), Catch::Contains("not a directory"));
  // A plain event file in our format: events but no labels.
  {
    StreamInfo info;
    info.width = 346, info.height = 260;
    auto w = open_yelan_h5_writer(d / "plain.yelan.h5", info);
    const std::vector<Event> ev = {{10, 1, 2, 1}, {20, 3, 4, 0}};
    w->write(ev);
    w->close();
  }
  CHECK_THROWS_WITH(read_recording_info(d / "plain.yelan.h5"), Catch::Contains("plain.yelan.h5") && Catch::Contains("labels"));
  std::ofstream(d / "junk.yelan.h5") << "not hdf5";
  CHECK_THROWS_WITH(read_recording_info(d / "junk.yelan.h5"), Catch::Contains("junk.yelan.h5"));
  // Too short for a window after the warm-up.
  const std::string shortrec = record(d, "ben-dance3-front-high-static", 0.12);
  WindowStreamOptions o;
  o.window = 8;
  o.shuffle = true;
  RecordingWindowStream s({shortrec}, 1, o);
  SimWindow w;
  CHECK_THROWS_WITH(s.next(w), Catch::Contains("too short"));
}

// Found by fuzz_recording: a labels/t claiming more rows than a vector can hold threw
// std::length_error past the reader's error handling and ended the program.
TEST_CASE("recording windows: a label dataset claiming more rows than the file stores is refused, naming it", "[sim]") {
  Dir d;
  const std::string path = record(d, "ben-dance3-front-high-static", 0.3);
  const std::size_t rows = read_recording_info(path).label_t.size();
  for (const hsize_t claim : {hsize_t(1) << 62, hsize_t(1) << 40, hsize_t(1) << 22}) {
    claim_unwritten(path, "labels/t", H5T_STD_I64LE, {claim}, {1024});
    CHECK_THROWS_AS(read_recording_info(path), FormatError);
    CHECK_THROWS_WITH(read_recording_info(path), Catch::Contains("labels/t") && Catch::Contains("rows"));
  }
  CHECK(rows > 10);  // the untouched recording was read whole
  // The same for the mask pictures, each camera-sized as a real one.
  std::filesystem::rename(path, d / "labels.yelan.h5");
  const std::string path2 = record(d, "ben-dance3-front-high-static", 0.3);
  CHECK(read_recording_masks(path2, 0, 4).size() == 4u * 346 * 260);
  claim_unwritten(path2, "masks/data", H5T_STD_U8LE, {hsize_t(1) << 40, 260, 346}, {1, 260, 346});
  CHECK_THROWS_WITH(read_recording_masks(path2, 0, 4), Catch::Contains("masks/data") && Catch::Contains("stores"));
}

TEST_CASE("recording windows: with history_s the TORE is yelan run's (every event of the file so far), anywhere in it", "[sim]") {
  Dir d;
  const std::string path = record(d, "ana-05_04-left-medium-dynamic", 0.8);
  const RecordingInfo info = read_recording_info(path);
  auto reader = open_event_file(path);
  std::vector<Event> ev;
  while (reader->read(ev, 1 << 16) > 0) {
  }
  REQUIRE(!ev.empty());
  WindowStreamOptions o;
  o.window = 2;
  o.warmup_s = 0.1;
  o.shuffle = true;
  // TORE keeps the whole file's history in `yelan run`; a window late in the file must see
  // it too, not only the warm-up. Without history_s it does not (the test can fail).
  for (const double history : {0.0, 5.0}) {
    o.history_s = history;
    RecordingWindowStream stream({path}, 7, o);
    int late = 0;
    for (int k = 0; k < 12; ++k) {
      SimWindow w;
      stream.next(w);
      const SimFrame& f = w.frames[1];
      if (f.t_us - ev.front().t < 400000) continue;  // early windows: the two agree anyway
      ++late;
      ToreVolume all(346, 260, o.tore);
      for (const Event& e : ev)
        if (e.t <= f.t_us) all.update(e);
      std::vector<float> want(all.volume_size());
      all.readout(f.t_us, want.data());
      if (history > 0) CHECK(f.tore == want);
      else CHECK(f.tore != want);
    }
    CHECK(late > 0);
  }
}

namespace {
// Two recordings read by cursors, several windows per visit, with yelan run's history.
std::vector<std::string> two_recordings(const Dir& d) {
  return {record(d, "ben-dance3-front-high-static", 0.9), record(d, "ana-05_04-left-medium-dynamic", 0.9)};
}
WindowStreamOptions cursor_options(int window, int per_visit) {
  WindowStreamOptions o;
  o.window = window;
  o.warmup_s = 0.1;
  o.history_s = 5;
  o.shuffle = true;
  o.cursors = 2;
  o.windows_per_visit = per_visit;
  return o;
}
}  // namespace

TEST_CASE("recording windows: cursors reading several windows per visit equal seeking each one, so resume is exact", "[sim]") {
  Dir d;
  const std::vector<std::string> paths = two_recordings(d);
  WindowStreamOptions o = cursor_options(2, 4);
  o.counts = true;
  RecordingWindowStream whole(paths, 3, o);
  std::vector<SimWindow> all(14);
  for (auto& w : all) whole.next(w);
  // Within a visit a cursor's windows come in increasing time, read on without seeking.
  CHECK(all[2].scene == all[0].scene);
  CHECK(all[2].frames[0].t_us > all[0].frames[1].t_us);
  RecordingWindowStream resumed(paths, 3, o);
  resumed.seek_window(5);  // mid-visit: every cursor starts afresh
  for (std::size_t k = 5; k < all.size(); ++k) {
    SimWindow w;
    resumed.next(w);
    INFO("window " << k);
    CHECK(w.scene == all[k].scene);
    REQUIRE(w.frames.size() == all[k].frames.size());
    for (std::size_t f = 0; f < w.frames.size(); ++f) {
      CHECK(w.frames[f].t_us == all[k].frames[f].t_us);
      CHECK(w.frames[f].tore == all[k].frames[f].tore);
      CHECK(w.frames[f].counts == all[k].frames[f].counts);
    }
  }
}

TEST_CASE("recording windows: tore_frames leaves the later frames' TORE out and the rest as it was", "[sim]") {
  Dir d;
  const std::vector<std::string> paths = two_recordings(d);
  WindowStreamOptions o = cursor_options(4, 3);
  RecordingWindowStream all_frames(paths, 5, o);
  o.tore_frames = 1;
  RecordingWindowStream first_only(paths, 5, o);
  for (int k = 0; k < 10; ++k) {
    SimWindow a, b;
    all_frames.next(a);
    first_only.next(b);
    INFO("window " << k);
    CHECK(b.scene == a.scene);
    REQUIRE(b.frames.size() == a.frames.size());
    for (std::size_t f = 0; f < a.frames.size(); ++f) {
      CHECK(b.frames[f].t_us == a.frames[f].t_us);
      CHECK(b.frames[f].mask == a.frames[f].mask);
      CHECK(b.frames[f].joints_mm == a.frames[f].joints_mm);
      REQUIRE_FALSE(a.frames[f].tore.empty());
      if (f == 0) CHECK(b.frames[f].tore == a.frames[f].tore);  // fed on from a window whose later frames were skipped
      else CHECK(b.frames[f].tore.empty());
    }
  }
}

TEST_CASE("recording windows: a batch read on two threads equals the same windows read one by one", "[sim]") {
  Dir d;
  const std::vector<std::string> paths = two_recordings(d);
  WindowStreamOptions o = cursor_options(3, 2);
  o.cursors = 3;  // more cursors than files: two of them may read one file at once
  o.counts = true;
  RecordingWindowStream serial(paths, 7, o), batched(paths, 7, o);
  std::vector<SimWindow> one_by_one(13);
  for (auto& w : one_by_one) serial.next(w);
  std::vector<SimWindow> got;
  // Batches that start mid-way through the cursors and straddle a visit's end.
  for (const std::size_t n : {2u, 1u, 5u, 4u, 1u}) {
    std::vector<SimWindow> part(n);
    batched.next_batch(part, 2);
    got.insert(got.end(), part.begin(), part.end());
  }
  REQUIRE(got.size() == one_by_one.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    INFO("window " << k);
    CHECK(got[k].scene == one_by_one[k].scene);
    REQUIRE(got[k].frames.size() == one_by_one[k].frames.size());
    for (std::size_t f = 0; f < got[k].frames.size(); ++f) {
      const SimFrame &a = got[k].frames[f], &b = one_by_one[k].frames[f];
      CHECK(a.t_us == b.t_us);
      REQUIRE_FALSE(a.tore.empty());
      // Compared as booleans: a failure printing two 2 MB volumes helps nobody.
      const bool same_tore = a.tore == b.tore, same_counts = a.counts == b.counts, same_mask = a.mask == b.mask;
      CHECK(same_tore);
      CHECK(same_counts);
      CHECK(same_mask);
      CHECK(a.joints_mm == b.joints_mm);
    }
  }
}
