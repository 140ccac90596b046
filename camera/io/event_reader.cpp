#include "camera/io/event_reader.h"

#include <algorithm>

namespace yelan::camera {

bool EventReader::fill() {
  if (head_ < pending_.size()) return true;
  pending_.clear();
  head_ = 0;
  while (!ended_ && pending_.empty()) {
    if (!decode(pending_)) ended_ = true;
    check(0);
  }
  return !pending_.empty();
}

// Drops events outside the sensor and counts timestamps that go backwards.
void EventReader::check(std::size_t from) {
  const std::uint64_t where = position();
  std::size_t keep = from;
  for (std::size_t i = from; i < pending_.size(); ++i) {
    const Event& e = pending_[i];
    if ((info_.width > 0 && e.x >= info_.width) || (info_.height > 0 && e.y >= info_.height)) {
      if (warnings_.out_of_range++ == 0)
        note_warning(where, "event at (" + std::to_string(e.x) + ", " + std::to_string(e.y) +
                                ") is outside the " + std::to_string(info_.width) + "x" +
                                std::to_string(info_.height) + " sensor (dropped)");
      continue;
    }
    // Any two timestamps in +-2^60 us (36,000 years) differ by less than 2^61: time
    // arithmetic downstream (durations, tick gaps) cannot overflow.
    constexpr std::int64_t kMaxAbsT = std::int64_t(1) << 60;
    if (e.t > kMaxAbsT || e.t < -kMaxAbsT)
      throw FormatError(path_, where, "timestamp " + std::to_string(e.t) + " us is outside +-2^60 us");
    if (have_last_ && e.t < last_t_) {
      if (warnings_.backwards++ == 0)
        note_warning(where, "timestamp goes backwards from " + std::to_string(last_t_) + " to " +
                                std::to_string(e.t) + " us");
    }
    have_last_ = true;
    last_t_ = e.t;
    pending_[keep++] = e;
  }
  pending_.resize(keep);
}

std::size_t EventReader::read(std::vector<Event>& out, std::size_t max_events) {
  std::size_t n = 0;
  while (n < max_events && fill()) {
    std::size_t take = std::min(max_events - n, pending_.size() - head_);
    out.insert(out.end(), pending_.begin() + head_, pending_.begin() + head_ + take);
    head_ += take;
    n += take;
  }
  return n;
}

std::size_t EventReader::read_until(std::vector<Event>& out, std::int64_t t_end, std::size_t max_events) {
  std::size_t n = 0;
  while (n < max_events && fill()) {
    if (pending_[head_].t >= t_end) break;
    out.push_back(pending_[head_++]);
    ++n;
  }
  return n;
}

std::optional<std::int64_t> EventReader::peek_time() {
  if (!fill()) return std::nullopt;
  return pending_[head_].t;
}

void EventReader::rewind() {
  restart();
  pending_.clear();
  head_ = 0;
  ended_ = false;
  have_last_ = false;
  warnings_ = {};
}

void EventReader::seek(std::int64_t t) {
  rewind();
  if (seek_index(t)) have_last_ = false;
  while (fill()) {
    while (head_ < pending_.size() && pending_[head_].t < t) ++head_;
    if (head_ < pending_.size()) return;
  }
}

void EventReader::warn_skipped(std::uint64_t offset, const std::string& what, std::uint64_t count) {
  if (count == 0) return;
  if (warnings_.skipped == 0) note_warning(offset, what);
  warnings_.skipped += count;
}

void EventReader::note_warning(std::uint64_t offset, const std::string& what) {
  if (warnings_.first.empty()) warnings_.first = "offset " + std::to_string(offset) + ": " + what;
}

}  // namespace yelan::camera
