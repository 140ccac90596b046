// Writing event files: ours (HDF5), AEDAT 4.0 and text. Writers stream (bounded memory) into
// a TempFile (camera/io/temp_file.h) renamed over `out` in close(), so a crash or an error
// never leaves a half-written file under the real name. A writer destroyed without close()
// removes its temporary file.
#pragma once
#include <memory>
#include <span>
#include <string>

#include "camera/event.h"
#include "camera/io/event_reader.h"
#include "camera/io/temp_file.h"

namespace yelan::camera {

class EventWriter {
 public:
  virtual ~EventWriter() = default;
  virtual void write(std::span<const Event> events) = 0;
  // Finishes the file and moves it to its final name.
  virtual void close() = 0;
};

// The output format for a path: "yelan-h5" (.yelan.h5, .h5), "aedat4" (.aedat4), "text" (.txt);
// empty when the extension names none of them.
std::string writer_format_for(const std::string& path);

// `info` gives the sensor size (0 = unknown) written into the file's header.
std::unique_ptr<EventWriter> open_event_writer(const std::string& path, const StreamInfo& info);

std::unique_ptr<EventWriter> open_text_writer(const std::string& path, const StreamInfo& info);
std::unique_ptr<EventWriter> open_aedat4_writer(const std::string& path, const StreamInfo& info);
std::unique_ptr<EventWriter> open_yelan_h5_writer(const std::string& path, const StreamInfo& info);
// The open HDF5 file (an hid_t) behind a writer from open_yelan_h5_writer, so a labelled
// recording can add its groups (camera, labels, masks) before close(); throws
// std::invalid_argument for any other writer.
std::int64_t yelan_h5_file(EventWriter& writer);

}  // namespace yelan::camera
