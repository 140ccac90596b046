// Event streams from files: one interface for every format, read in batches (by count or by
// time window) in bounded memory. Bad bytes throw FormatError; things a format tolerates
// (timestamps going backwards, coordinates outside the sensor, unknown words) are counted in
// warnings() and never silently fixed.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "camera/event.h"
#include "camera/io/format_error.h"

namespace yelan::camera {

struct StreamInfo {
  std::string format;  // "evt2", "evt21", "evt3", "aedat4", "text", "yelan-h5", "dsec-h5", ...
  int width = 0, height = 0;              // sensor size; 0 when the file does not say
  std::optional<std::int64_t> t_first;    // known without decoding events (indexed formats)
  std::optional<std::uint64_t> events;    // event count, when the file states it
};

struct ReadWarnings {
  std::uint64_t backwards = 0;     // events earlier than the event before them (kept as read)
  std::uint64_t out_of_range = 0;  // events outside the sensor (dropped)
  std::uint64_t skipped = 0;       // words or records the decoder could not use (dropped)
  std::string first;               // the first warning, "offset N: what"
  std::uint64_t total() const { return backwards + out_of_range + skipped; }
};

class EventReader {
 public:
  virtual ~EventReader() = default;
  EventReader(const EventReader&) = delete;
  EventReader& operator=(const EventReader&) = delete;

  const std::string& path() const { return path_; }
  const StreamInfo& info() const { return info_; }
  const ReadWarnings& warnings() const { return warnings_; }

  // Appends up to max_events events to out; returns how many (0 only at the end).
  std::size_t read(std::vector<Event>& out, std::size_t max_events);
  // Appends the next events with t < t_end, at most max_events of them (call again while it
  // returns max_events: a window may hold more events than one batch).
  std::size_t read_until(std::vector<Event>& out, std::int64_t t_end, std::size_t max_events);
  // The time of the next event, without consuming it; nullopt at the end.
  std::optional<std::int64_t> peek_time();

  // Positions the stream on the first event with t >= t (in file order). Formats with an index
  // jump there (fast_seek()); the others decode from the start.
  void seek(std::int64_t t);
  void rewind();
  virtual bool fast_seek() const { return false; }

  // How far the decoder has got in the file (for progress), and the file size.
  virtual std::uint64_t position() const = 0;
  virtual std::uint64_t file_size() const = 0;

 protected:
  explicit EventReader(std::string path) : path_(std::move(path)) {}
  // Decodes the next piece of the file, appending its events (possibly none) to out.
  // Returns false at the end of the stream.
  virtual bool decode(std::vector<Event>& out) = 0;
  // Back to the first event.
  virtual void restart() = 0;
  // Formats with an index: position the decoder at or before the first event with t >= t.
  virtual bool seek_index(std::int64_t /*t*/) { return false; }

  void warn_skipped(std::uint64_t offset, const std::string& what, std::uint64_t count = 1);
  void note_warning(std::uint64_t offset, const std::string& what);

  std::string path_;
  StreamInfo info_;

 private:
  bool fill();  // refills pending_; false at the end
  void check(std::size_t from);

  ReadWarnings warnings_;
  std::vector<Event> pending_;
  std::size_t head_ = 0;
  bool ended_ = false;
  bool have_last_ = false;
  std::int64_t last_t_ = 0;
};

// Opens any supported event file: the format is told by its magic bytes or header, then by
// its extension. Throws FormatError when the file is not a readable event file.
std::unique_ptr<EventReader> open_event_file(const std::string& path);

// The format name open_event_file would use, without decoding the stream.
std::string detect_event_format(const std::string& path);

}  // namespace yelan::camera
