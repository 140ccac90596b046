// One opener per format; open_event_file picks among them.
#pragma once
#include <memory>
#include <string>

#include "camera/io/event_reader.h"

namespace yelan::camera {

std::unique_ptr<EventReader> open_prophesee_raw(const std::string& path);
std::unique_ptr<EventReader> open_aedat4(const std::string& path);
std::unique_ptr<EventReader> open_text_events(const std::string& path);
// HDF5: ours (root attribute format="yelan-recording"), DSEC (events/{x,y,p,t}, t_offset,
// ms_to_idx) or v2e (an Nx4 `events` dataset: t, x, y, p).
std::unique_ptr<EventReader> open_hdf5_events(const std::string& path);
std::unique_ptr<EventReader> open_npy_events(const std::string& path);

}  // namespace yelan::camera
