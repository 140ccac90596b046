// `yelan info` and `yelan convert`: event files through camera/io. Bad input (a FormatError)
// exits 2 with `yelan: error: FILE: offset N: problem`.
#include <unistd.h>

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "camera/io/aedat_legacy.h"
#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"

namespace yelan::cli {
namespace {

constexpr std::size_t kBatch = 1 << 16;

struct Summary {
  std::uint64_t events = 0, on = 0;
  std::int64_t t_first = 0, t_last = 0;
  int x_max = -1, y_max = -1;
};

void add(Summary& s, const std::vector<camera::Event>& batch) {
  for (const camera::Event& e : batch) {
    if (s.events == 0) s.t_first = e.t;
    s.t_last = e.t;
    ++s.events;
    s.on += e.p;
    s.x_max = std::max<int>(s.x_max, e.x);
    s.y_max = std::max<int>(s.y_max, e.y);
  }
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') o += '\\', o += static_cast<char>(c);
    else if (c < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      o += b;
    } else o += static_cast<char>(c);
  }
  return o + "\"";
}

double rate_hz(const Summary& s) {
  const std::int64_t span = s.t_last - s.t_first;
  return span > 0 ? static_cast<double>(s.events) * 1e6 / static_cast<double>(span) : 0.0;
}

void print_json(std::ostream& out, const std::string& path, const camera::EventReader& r, const Summary& s) {
  const auto& w = r.warnings();
  const bool any = s.events > 0;
  std::ostringstream o;
  o << "{\"file\": " << json_string(path) << ", \"format\": " << json_string(r.info().format)
    << ", \"width\": " << r.info().width << ", \"height\": " << r.info().height << ", \"events\": " << s.events
    << ", \"on_events\": " << s.on << ", \"off_events\": " << (s.events - s.on);
  if (any) {
    o << ", \"t_first_us\": " << s.t_first << ", \"t_last_us\": " << s.t_last
      << ", \"duration_us\": " << (s.t_last - s.t_first) << std::fixed << std::setprecision(1)
      << ", \"event_rate_hz\": " << rate_hz(s) << std::setprecision(6)
      << ", \"on_fraction\": " << static_cast<double>(s.on) / static_cast<double>(s.events)
      << ", \"x_max\": " << s.x_max << ", \"y_max\": " << s.y_max;
  } else {
    o << ", \"t_first_us\": null, \"t_last_us\": null, \"duration_us\": 0, \"event_rate_hz\": 0"
         ", \"on_fraction\": null, \"x_max\": null, \"y_max\": null";
  }
  o << ", \"warnings\": {\"backwards\": " << w.backwards << ", \"out_of_range\": " << w.out_of_range
    << ", \"skipped\": " << w.skipped << ", \"first\": " << (w.first.empty() ? "null" : json_string(w.first))
    << "}}\n";
  out << o.str();
}

void print_text(std::ostream& out, const std::string& path, const camera::EventReader& r, const Summary& s) {
  const auto& info = r.info();
  std::ostringstream o;
  o << "file:      " << path << "\n"
    << "format:    " << info.format << "\n"
    << "sensor:    " << (info.width > 0 ? std::to_string(info.width) + "x" + std::to_string(info.height) : "unknown")
    << "\n"
    << "events:    " << s.events;
  if (s.events) {
    o << std::fixed << std::setprecision(1) << " (ON " << s.on << " = " << 100.0 * s.on / s.events << "%, OFF "
      << s.events - s.on << ")\n"
      << "time:      " << s.t_first << " .. " << s.t_last << " us (" << std::setprecision(3)
      << (s.t_last - s.t_first) / 1000.0 << " ms)\n"
      << "rate:      " << std::setprecision(3) << rate_hz(s) / 1e6 << " Mev/s\n"
      << "x/y max:   " << s.x_max << ", " << s.y_max << "\n";
  } else {
    o << "\n";
  }
  const auto& w = r.warnings();
  if (w.total() == 0) o << "warnings:  none\n";
  else
    o << "warnings:  " << w.backwards << " backwards timestamps, " << w.out_of_range << " outside the sensor, "
      << w.skipped << " skipped; first: " << w.first << "\n";
  out << o.str();
}

void print_warnings(std::ostream& err, const std::string& path, const camera::EventReader& r) {
  const auto& w = r.warnings();
  if (w.total() == 0) return;
  err << "yelan: warning: " << path << ": " << w.backwards << " backwards timestamps, " << w.out_of_range
      << " events outside the sensor, " << w.skipped << " skipped; first at " << w.first << "\n";
}

int format_error(std::ostream& err, const camera::FormatError& e) {
  err << "yelan: error: " << printable(e.what()) << "\n";
  return kUsageError;
}

bool stderr_is_tty(const std::ostream& err) { return &err == &std::cerr && ::isatty(STDERR_FILENO); }

void progress_bar(std::ostream& err, double fraction, std::uint64_t events) {
  const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
  err << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
      << std::string(static_cast<std::size_t>(width - filled), ' ') << "] " << std::setw(3)
      << static_cast<int>(fraction * 100 + 0.5) << "%  " << events << " events" << std::flush;
}

// --camera N picks one of DHP19's four cameras (address & 0xF) in an AEDAT 2.0 file.
std::unique_ptr<camera::EventReader> open_input(const std::string& path, const Args& args) {
  const auto cam = args.value("--camera");
  if (!cam) return camera::open_event_file(path);
  const int n = args.int_value_or("--camera", 0, 0, 15);
  if (camera::detect_event_format(path) != "aedat-old")
    throw UsageError("--camera " + *cam + " applies to AEDAT 2.0 files (DHP19's multiplexed cameras) only");
  return camera::open_aedat_legacy(path, n);
}

}  // namespace

int cmd_info(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  Args args("info", argv, {"--camera"}, {"--json"});
  args.expect_positionals(1, 1);
  const std::string& path = args.positionals()[0];
  try {
    auto reader = open_input(path, args);
    Summary s;
    std::vector<camera::Event> batch;
    while (true) {
      batch.clear();
      if (reader->read(batch, kBatch) == 0) break;
      add(s, batch);
    }
    if (args.flag("--json")) print_json(out, path, *reader, s);
    else print_text(out, path, *reader, s);
  } catch (const camera::FormatError& e) {
    return format_error(err, e);
  }
  return kOk;
}

int cmd_convert(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  (void)out;
  Args args("convert", argv, {"--camera"}, {});
  args.expect_positionals(2, 2);
  const std::string& in = args.positionals()[0];
  const std::string& dst = args.positionals()[1];
  if (camera::writer_format_for(dst).empty())
    throw UsageError("cannot tell the output format of '" + dst + "' (use .yelan.h5, .h5, .aedat4 or .txt)");
  check_output("OUT", dst, {in});
  try {
    auto reader = open_input(in, args);
    auto writer = camera::open_event_writer(dst, reader->info());
    const bool tty = stderr_is_tty(err);
    int last_percent = -1;
    Summary s;
    std::vector<camera::Event> batch;
    while (true) {
      batch.clear();
      if (reader->read(batch, kBatch) == 0) break;
      writer->write(batch);
      add(s, batch);
      if (tty && reader->file_size() > 0) {
        const double f = static_cast<double>(reader->position()) / static_cast<double>(reader->file_size());
        if (static_cast<int>(f * 100) != last_percent) {  // redraw only when the number changes
          last_percent = static_cast<int>(f * 100);
          progress_bar(err, f, s.events);
        }
      }
    }
    writer->close();
    if (tty) {
      progress_bar(err, 1.0, s.events);
      err << "\n";
    }
    print_warnings(err, in, *reader);
    err << "yelan convert: " << in << " (" << reader->info().format << ") -> " << dst << " ("
        << camera::writer_format_for(dst) << "): " << s.events << " events\n";
  } catch (const camera::FormatError& e) {
    return format_error(err, e);
  }
  return kOk;
}

}  // namespace yelan::cli
