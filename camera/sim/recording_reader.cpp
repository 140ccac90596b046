#include "camera/sim/recording_reader.h"

#include <hdf5.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "camera/io/event_reader.h"
#include "camera/io/format_error.h"
#include "camera/io/untrusted.h"

namespace yelan::camera::sim {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSuffix = ".yelan.h5";

[[noreturn]] void fail(const std::string& path, const std::string& what) { recording_error(path, what); }

std::string bytes_text(double bytes) {
  char b[40];
  std::snprintf(b, sizeof b, "%.3g bytes", bytes);
  return b;
}

// A corrupt file can claim a dataset of any size, and the reader sizes its buffer from the
// claim; deflate expands at most ~1032 times, so what the file stores bounds a real claim.
void require_stored(hid_t ds, const std::string& path, const std::string& name, const std::vector<hsize_t>& dims,
                    std::size_t element_bytes) {
  const std::uint64_t stored = H5Dget_storage_size(ds);
  double claimed = double(element_bytes);
  for (hsize_t d : dims) claimed *= double(d);
  if (claimed > double(1 << 20) + double(stored) * 1100)
    fail(path, name + " claims " + std::to_string(dims.empty() ? 1 : dims[0]) + " rows (" + bytes_text(claimed) +
                   ") but stores " + bytes_text(double(stored)));
}

// Rows of an N x (row dims) dataset, all of them, as mem_type; checks the row shape.
template <class T>
std::vector<T> read_all(hid_t f, const std::string& path, const std::string& name, hid_t mem_type,
                        const std::vector<hsize_t>& row) {
  if (!h5::exists(f, name)) fail(path, "no dataset " + name + " (not a labelled recording from `yelan sim`)");
  h5::H5Id ds = h5::check(H5Dopen2(f, name.c_str(), H5P_DEFAULT), "open " + name);
  h5::require_numeric(ds.get(), name);
  const std::vector<hsize_t> dims = h5::shape(ds.get());
  if (dims.size() != row.size() + 1 || !std::equal(row.begin(), row.end(), dims.begin() + 1))
    fail(path, name + " has the wrong shape");
  std::size_t per = 1;
  for (hsize_t d : row) per *= std::size_t(d);
  constexpr std::size_t kMaxElements = std::size_t(1) << 26;  // hours of labels at 300 Hz
  if (dims[0] > kMaxElements / per) fail(path, name + " claims " + std::to_string(dims[0]) + " rows, more than a recording holds");
  require_stored(ds.get(), path, name, dims, sizeof(T));
  std::vector<T> out(std::size_t(dims[0]) * per);
  if (!out.empty()) h5::check(H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), "read " + name);
  return out;
}


// Everything a reader of the recording will touch: labels, cameras, every mask, every event.
void read_whole_recording(const std::string& path) {
  h5::silence_errors();
  const h5::H5Id f = h5::open_file(path);
  const RecordingInfo info = read_recording_info(f.get(), path);
  h5::H5Id masks = h5::check(H5Dopen2(f.get(), "masks/data", H5P_DEFAULT), "open masks/data");
  h5::require_numeric(masks.get(), "masks/data");
  const auto dims = h5::shape(masks.get());
  if (dims.size() != 3 || dims[1] != hsize_t(info.camera.height) || dims[2] != hsize_t(info.camera.width)) return;
  require_stored(masks.get(), path, "masks/data", dims, 1);
  std::vector<std::uint8_t> one(std::size_t(dims[1]) * dims[2]);
  for (hsize_t m = 0; m < dims[0]; ++m) {
    const hsize_t start[3] = {m, 0, 0}, count[3] = {1, dims[1], dims[2]};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select mask");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, one.data()), "read mask");
  }
  auto events = open_event_file(path);
  std::vector<Event> v;
  while (events->read(v, 1 << 20)) v.clear();
}

}  // namespace

// A FormatError: a malformed recording is bad input (exit 2), as any other malformed file.
void recording_error(const std::string& path, const std::string& what) { throw FormatError(path, 0, what); }

std::size_t vet_recordings(const std::vector<std::string>& paths, int jobs) {
  h5::silence_errors();
  return vet_all_in_children(paths, [](const std::string& p) { read_whole_recording(p); }, jobs);
}

h5::H5Id open_recording(const std::string& path) {
  h5::silence_errors();
  vet_in_child(path, [&] { read_whole_recording(path); });
  try {
    return h5::open_file(path);
  } catch (const std::exception& e) {
    fail(path, std::string("cannot open as HDF5: ") + e.what());
  }
}

// Everything but the events and the mask pictures, from an open file.
RecordingInfo read_recording_info(hid_t f, const std::string& path) {
  RecordingInfo r;
  r.path = path;
  r.name = fs::path(path).filename().string();
  if (r.name.size() > std::string(kSuffix).size() && r.name.ends_with(kSuffix))
    r.name.resize(r.name.size() - std::string(kSuffix).size());
  if (!h5::exists(f, "labels/t") || !h5::exists(f, "masks/t"))
    fail(path, "no labels/t or masks/t: an event file, not a labelled recording (`yelan sim` writes those)");
  try {
    const auto w = h5::read_scalar_i64(f, "camera/width"), h = h5::read_scalar_i64(f, "camera/height");
    if (!w || !h || *w < 1 || *h < 1 || *w > 65536 || *h > 65536) fail(path, "no valid camera/width and camera/height");
    r.camera.width = int(*w);
    r.camera.height = int(*h);
    const auto k = read_all<double>(f, path, "camera/K", H5T_NATIVE_DOUBLE, {3});
    if (k.size() != 9) fail(path, "camera/K is not 3x3");
    r.camera.fx = k[0], r.camera.fy = k[4], r.camera.cx = k[2], r.camera.cy = k[5];
    r.character = h5::read_attr_string(f, "character").value_or("");
    r.motion = h5::read_attr_string(f, "motion").value_or("");
    r.view = h5::read_attr_string(f, "view").value_or("");
    r.lighting = h5::read_attr_string(f, "lighting").value_or("");
    r.background = h5::read_attr_string(f, "background").value_or("");
    if (const auto dancer = h5::read_attr_i64(f, "dancer")) r.dancer = *dancer != 0;
    if (const auto scene = h5::read_attr_string(f, "scene")) {
      const auto j = nlohmann::json::parse(*scene, nullptr, false);
      if (!j.is_discarded() && j.contains("occluders") && j["occluders"].is_boolean()) r.occluded = j["occluders"].get<bool>();
    }
    r.label_t = read_all<std::int64_t>(f, path, "labels/t", H5T_NATIVE_INT64, {});
    r.joints = read_all<float>(f, path, "labels/joints", H5T_NATIVE_FLOAT, {hsize_t(kJointCount), 3});
    r.valid = read_all<std::uint8_t>(f, path, "labels/valid", H5T_NATIVE_UINT8, {hsize_t(kJointCount)});
    r.mask_t = read_all<std::int64_t>(f, path, "masks/t", H5T_NATIVE_INT64, {});
  } catch (const h5::H5Failure& e) {
    fail(path, e.what());
  }
  if (r.joints.size() != r.label_t.size() * kJointCount * 3 || r.valid.size() != r.label_t.size() * kJointCount)
    fail(path, "labels/t, labels/joints and labels/valid differ in length");
  if (r.label_t.empty() || r.mask_t.size() < 2) fail(path, "no labels or fewer than two masks");
  for (std::size_t i = 1; i < r.label_t.size(); ++i)
    if (r.label_t[i] <= r.label_t[i - 1]) fail(path, "labels/t is not increasing at row " + std::to_string(i));
  for (std::size_t i = 1; i < r.mask_t.size(); ++i)
    if (r.mask_t[i] <= r.mask_t[i - 1]) fail(path, "masks/t is not increasing at row " + std::to_string(i));
  return r;
}

void label_at(const RecordingInfo& info, std::int64_t t_us, Joints13& joints, std::array<std::uint8_t, kJointCount>& valid) {
  const auto& lt = info.label_t;
  if (lt.empty()) throw std::invalid_argument(info.path + ": no labels");
  std::size_t b = std::size_t(std::upper_bound(lt.begin(), lt.end(), t_us) - lt.begin());
  const std::size_t a = b == 0 ? 0 : b - 1;
  if (b >= lt.size()) b = lt.size() - 1;
  const double w = (b == a || lt[b] == lt[a]) ? 0.0 : double(t_us - lt[a]) / double(lt[b] - lt[a]);
  const double wa = 1 - std::clamp(w, 0.0, 1.0), wb = 1 - wa;
  for (int k = 0; k < kJointCount; ++k) {
    for (int d = 0; d < 3; ++d)
      joints[k][d] = wa * info.joints[(a * kJointCount + k) * 3 + d] + wb * info.joints[(b * kJointCount + k) * 3 + d];
    valid[k] = info.valid[a * kJointCount + k] && info.valid[b * kJointCount + k];
  }
}

RecordingInfo read_recording_info(const std::string& path) {
  const h5::H5Id file = open_recording(path);
  return read_recording_info(file.get(), path);
}

std::vector<std::uint8_t> read_recording_masks(const std::string& path, std::size_t first, std::size_t n) {
  const h5::H5Id file = open_recording(path);
  try {
    h5::H5Id masks = h5::check(H5Dopen2(file.get(), "masks/data", H5P_DEFAULT), "open masks/data");
    h5::require_numeric(masks.get(), "masks/data");
    const auto dims = h5::shape(masks.get());
    if (dims.size() != 3) fail(path, "masks/data is not masks x height x width");
    // The picture size is the camera's: a file declaring larger masks must not size the buffer.
    const auto w = h5::read_scalar_i64(file.get(), "camera/width"), h = h5::read_scalar_i64(file.get(), "camera/height");
    if (!w || !h || *w < 1 || *h < 1 || *w > 65536 || *h > 65536 || dims[1] != hsize_t(*h) || dims[2] != hsize_t(*w))
      fail(path, "masks/data is not masks x camera/height x camera/width");
    require_stored(masks.get(), path, "masks/data", dims, 1);
    if (first >= dims[0]) return {};
    n = std::min<std::size_t>(n, std::size_t(dims[0]) - first);
    std::vector<std::uint8_t> out(n * std::size_t(dims[1]) * dims[2]);
    const hsize_t start[3] = {hsize_t(first), 0, 0}, count[3] = {hsize_t(n), dims[1], dims[2]};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select masks");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    if (n) h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, out.data()), "read masks");
    return out;
  } catch (const h5::H5Failure& e) {
    fail(path, e.what());
  }
}

std::vector<std::string> list_recordings(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a directory");
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().filename().string().ends_with(kSuffix)) out.push_back(e.path().string());
  if (ec) throw std::runtime_error(dir + ": " + ec.message());
  if (out.empty()) throw std::runtime_error(dir + ": no recordings (*.yelan.h5; `yelan sim --grid ... --out-dir` writes them)");
  std::sort(out.begin(), out.end());
  return out;
}

void split_by_recording(const std::vector<std::string>& all, std::vector<std::string>& train,
                        std::vector<std::string>& val) {
  if (all.size() < 2)
    throw std::runtime_error("validation is split by recording: need two recordings or more (or give validation data)");
  train.clear(), val.clear();
  for (std::size_t i = 0; i < all.size(); ++i) (i % 10 == 9 ? val : train).push_back(all[i]);
  if (val.empty()) {
    val.push_back(train.back());
    train.pop_back();
  }
}

}  // namespace yelan::camera::sim
