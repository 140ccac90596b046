// Labelled recordings on disk (*.yelan.h5 as `yelan sim` writes them: events, /camera,
// /labels at 300 Hz, /masks at the frame rate, the scene as attributes): what they hold,
// read and checked. A recording is HDF5 we may not have written, so it is read first in a
// child process (camera/io/untrusted.h) before this process opens it. Malformed files are
// FormatErrors naming the file (exit 2).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "camera/io/h5.h"
#include "camera/sim/types.h"

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

// The label at time t: joints linearly interpolated between the labels around t (clamped
// to the first and last); a joint is valid when both labels say so.
void label_at(const RecordingInfo& info, std::int64_t t_us, Joints13& joints, std::array<std::uint8_t, kJointCount>& valid);

// Masks first .. first + n - 1 of a recording (height x width bytes each, nonzero: the
// dancer), clamped to the masks it has. Throws FormatError naming the file.
std::vector<std::uint8_t> read_recording_masks(const std::string& path, std::size_t first, std::size_t n);

// The *.yelan.h5 files in dir, sorted by name. Throws when there are none.
std::vector<std::string> list_recordings(const std::string& dir);

// Splits recordings (sorted) by recording, never by frame: every tenth is for validation,
// and at least one when there are two or more. Throws with fewer than two.
void split_by_recording(const std::vector<std::string>& all, std::vector<std::string>& train,
                        std::vector<std::string>& val);

// Vets recordings before they are opened, `jobs` at a time (camera/io/untrusted.h): for a
// training or an evaluation about to open hundreds, called before it allocates its networks.
// Returns how many were read in a child (those not vetted before). Throws the first
// FormatError.
std::size_t vet_recordings(const std::vector<std::string>& paths, int jobs);

// For readers that keep the file open (RecordingWindowStream): the file, vetted and opened,
// and its info read from the open file.
h5::H5Id open_recording(const std::string& path);
RecordingInfo read_recording_info(hid_t file, const std::string& path);

// A FormatError naming the recording.
[[noreturn]] void recording_error(const std::string& path, const std::string& what);

}  // namespace yelan::camera::sim
