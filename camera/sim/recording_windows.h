// Labelled recordings on disk (*.yelan.h5 as `yelan sim` writes them: events, /camera,
// /labels at 300 Hz, /masks at the frame rate, the scene as attributes) as the same
// windows the simulator stream gives, so the trainer and the evaluator read either.
// Frames sit on the recording's mask times; the joints are interpolated there; the TORE
// starts empty warmup_s before a window's first frame, as in a freshly simulated scene.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "camera/sim/window_stream.h"

namespace yelan::camera::sim {

struct RecordingInfo {
  std::string path, name;           // name: the file name without .yelan.h5
  CameraModel camera;
  std::string character, motion, view, lighting, background;
  bool occluded = false;
  bool dancer = true;               // false: an empty scene (attribute dancer = 0)
  std::int64_t first_event_us = 0;
  std::vector<std::int64_t> label_t;
  std::vector<float> joints;        // label_t.size() x 13 x 3, mm, camera frame
  std::vector<std::uint8_t> valid;  // label_t.size() x 13
  std::vector<std::int64_t> mask_t;
};

// Reads everything but the events and the mask pictures. Throws std::runtime_error naming
// the file and what is missing or malformed.
RecordingInfo read_recording_info(const std::string& path);

// Masks first .. first + n - 1 of a recording (height x width bytes each, nonzero: the
// dancer), clamped to the masks it has. Throws FormatError naming the file.
std::vector<std::uint8_t> read_recording_masks(const std::string& path, std::size_t first, std::size_t n);

// The *.yelan.h5 files in dir, sorted by name. Throws when there are none.
std::vector<std::string> list_recordings(const std::string& dir);

// Splits recordings (sorted) by recording, never by frame: every tenth is for validation,
// and at least one when there are two or more. Throws with fewer than two.
void split_by_recording(const std::vector<std::string>& all, std::vector<std::string>& train,
                        std::vector<std::string>& val);

class RecordingWindowStream {
 public:
  // shuffle: window k comes from a seeded pick of recording and start frame (depends on k
  // alone, so a resumed trainer sees the same data); otherwise consecutive windows run
  // through each recording in turn, the TORE carried across them.
  RecordingWindowStream(std::vector<std::string> paths, std::uint64_t seed, WindowStreamOptions options);
  ~RecordingWindowStream();
  void next(SimWindow& out);
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
  void next_from_cursor(SimWindow& out);
};

}  // namespace yelan::camera::sim
