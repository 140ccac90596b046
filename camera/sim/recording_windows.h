// Labelled recordings on disk (camera/sim/recording_reader.h) as the same windows the
// simulator stream gives, so the trainer and the evaluator read either.
// Frames sit on the recording's mask times; the joints are interpolated there; the TORE
// starts empty warmup_s before a window's first frame, as in a freshly simulated scene.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "camera/sim/recording_reader.h"
#include "camera/sim/window_stream.h"

namespace yelan::camera::sim {

class RecordingWindowStream {
 public:
  // shuffle: window k comes from a seeded pick of recording and start frame (depends on k
  // alone, so a resumed trainer sees the same data); otherwise consecutive windows run
  // through each recording in turn, the TORE carried across them.
  RecordingWindowStream(std::vector<std::string> paths, std::uint64_t seed, WindowStreamOptions options);
  ~RecordingWindowStream();
  void next(SimWindow& out);
  // The next out.size() windows, equal to as many next() calls. With cursors, the windows of
  // different cursors are read on up to `threads` threads at once: each cursor's file, reader
  // and TORE are its own, and HDF5 (built thread-safe) serialises its calls.
  void next_batch(std::span<SimWindow> out, int threads);
  void seek_window(std::uint64_t k);
  // Consecutive mode: the windows that fit in recording i.
  int windows_in(std::size_t i);
  const RecordingInfo& info(std::size_t i);

 private:
  struct Open;
  Open& open(std::size_t i);
  void fill(Open& r, std::size_t first_mask, bool fresh, SimWindow& out);
  std::vector<std::string> paths_;
  std::uint64_t seed_;
  WindowStreamOptions opt_;
  std::uint64_t k_ = 0;              // windows served
  std::size_t seq_rec_ = 0, seq_mask_ = 0;
  bool seq_started_ = false;
  std::unique_ptr<Open> open_;  // the one recording open at a time (one cursor)
  struct Cursor {
    std::unique_ptr<Open> open;
    std::uint64_t visit = ~0ull;
    std::size_t end = 0;  // the mask index after the last window served
  };
  std::vector<Cursor> cursors_;
  // Where cursor mode's next window lies: the cursor's file opened (vetted) on a new visit,
  // the window's first mask and whether the reader must seek to it.
  struct Planned {
    Open* open = nullptr;
    std::size_t first = 0;
    bool fresh = true;
  };
  // Shuffled windows through cursors (several, or several windows a visit): plan_from_cursor.
  bool cursor_mode() const { return opt_.shuffle && (opt_.cursors > 1 || opt_.windows_per_visit > 1); }
  Planned plan_from_cursor();
  void read_planned(const Planned& p, SimWindow& out);
};

}  // namespace yelan::camera::sim
