// A simulated recording in our HDF5 format (SPEC section 2): the events through the
// ordinary writer, then /camera, /labels and /masks beside them, and the scene as root
// attributes. Labels and masks stream into growing datasets (bounded memory for any length).
#include <hdf5.h>

#include <cmath>
#include <optional>

#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "camera/sim/simulator.h"

namespace yelan::camera::sim {

namespace {

// An N-D dataset growing along its first dimension, chunked by one row, deflate-compressed.
class GrowingRows {
 public:
  GrowingRows(hid_t loc, const std::string& name, hid_t file_type, hid_t mem_type, std::vector<hsize_t> row,
              hsize_t rows_per_chunk)
      : mem_type_(mem_type), row_(std::move(row)) {
    std::vector<hsize_t> dims{0}, maxd{H5S_UNLIMITED}, chunk{rows_per_chunk};
    for (hsize_t d : row_) dims.push_back(d), maxd.push_back(d), chunk.push_back(d);
    h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), maxd.data()), "dataspace " + name);
    h5::H5Id props = h5::untimed_dataset_props();
    h5::check(H5Pset_chunk(props.get(), int(chunk.size()), chunk.data()), "chunking " + name);
    h5::check(H5Pset_deflate(props.get(), 4), "deflate " + name);
    ds_ = h5::check(H5Dcreate2(loc, name.c_str(), file_type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
                    "create " + name);
  }
  void append(const void* data) {
    std::vector<hsize_t> dims{n_ + 1}, start{n_}, count{1};
    for (hsize_t d : row_) dims.push_back(d), start.push_back(0), count.push_back(d);
    h5::check(H5Dset_extent(ds_.get(), dims.data()), "extend dataset");
    h5::H5Id file_space = h5::check(H5Dget_space(ds_.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
              "select rows");
    h5::H5Id mem_space = h5::check(H5Screate_simple(int(count.size()), count.data(), nullptr), "dataspace");
    h5::check(H5Dwrite(ds_.get(), mem_type_, mem_space.get(), file_space.get(), H5P_DEFAULT, data), "write rows");
    ++n_;
  }

 private:
  h5::H5Id ds_;
  hid_t mem_type_;
  std::vector<hsize_t> row_;
  hsize_t n_ = 0;
};

void write_matrix(hid_t loc, const std::string& name, int rows, int cols, const double* data) {
  const hsize_t dims[2] = {hsize_t(rows), hsize_t(cols)};
  h5::H5Id space = h5::check(H5Screate_simple(2, dims, nullptr), "dataspace " + name);
  h5::H5Id props = h5::untimed_dataset_props();
  h5::H5Id ds = h5::check(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
                          "create " + name);
  h5::check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
}

void write_scalar_i64(hid_t loc, const std::string& name, std::int64_t v) {
  h5::H5Id space = h5::check(H5Screate(H5S_SCALAR), "dataspace " + name);
  h5::H5Id props = h5::untimed_dataset_props();
  h5::H5Id ds = h5::check(H5Dcreate2(loc, name.c_str(), H5T_STD_I64LE, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
                          "create " + name);
  h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), "write " + name);
}

void write_camera(hid_t f, const CameraModel& cam) {
  h5::H5Id g = h5::create_group(f, "camera");
  const Eigen::Matrix3d k = cam.K();
  double kr[9], m[12], dist[5] = {0, 0, 0, 0, 0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) kr[r * 3 + c] = k(r, c);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) m[r * 4 + c] = cam.M(r, c);
  write_matrix(g.get(), "K", 3, 3, kr);
  write_matrix(g.get(), "M", 3, 4, m);
  write_matrix(g.get(), "dist", 1, 5, dist);
  write_scalar_i64(g.get(), "width", cam.width);
  write_scalar_i64(g.get(), "height", cam.height);
}

}  // namespace

struct RecordingWriter::Impl {
  std::unique_ptr<EventWriter> writer;
  h5::H5Id labels, masks;
  std::optional<GrowingRows> label_t, joints, valid, mask_t, mask;
};

RecordingWriter::RecordingWriter(const std::string& path, const Simulator& sim) : impl_(std::make_unique<Impl>()) {
  const CameraModel& cam = sim.camera();
  const SimSpec& spec = sim.spec();
  StreamInfo info;
  info.width = cam.width;
  info.height = cam.height;
  impl_->writer = open_yelan_h5_writer(path, info);
  const hid_t f = hid_t(yelan_h5_file(*impl_->writer));
  write_camera(f, cam);
  h5::write_attr_string(f, "scene", sim.description_json());
  h5::write_attr_string(f, "character", sim.character().name);
  h5::write_attr_string(f, "motion", spec.motion);
  h5::write_attr_string(f, "view", view_name(spec.scene.view));
  h5::write_attr_string(f, "lighting", light_name(spec.scene.light));
  h5::write_attr_string(f, "background", spec.scene.background == SceneConfig::dynamic ? "dynamic" : "static");
  h5::write_attr_i64(f, "seed", std::int64_t(spec.seed));
  h5::write_attr_i64(f, "dancer", spec.dancer ? 1 : 0);
  Impl& m = *impl_;
  m.labels = h5::create_group(f, "labels");
  m.masks = h5::create_group(f, "masks");
  m.label_t.emplace(m.labels.get(), "t", H5T_STD_I64LE, H5T_NATIVE_INT64, std::vector<hsize_t>{}, 1024);
  m.joints.emplace(m.labels.get(), "joints", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, std::vector<hsize_t>{kJointCount, 3}, 256);
  m.valid.emplace(m.labels.get(), "valid", H5T_STD_U8LE, H5T_NATIVE_UINT8, std::vector<hsize_t>{kJointCount}, 1024);
  m.mask_t.emplace(m.masks.get(), "t", H5T_STD_I64LE, H5T_NATIVE_INT64, std::vector<hsize_t>{}, 256);
  m.mask.emplace(m.masks.get(), "data", H5T_STD_U8LE, H5T_NATIVE_UINT8,
                 std::vector<hsize_t>{hsize_t(cam.height), hsize_t(cam.width)}, 1);
}

RecordingWriter::~RecordingWriter() = default;

void RecordingWriter::events(std::span<const Event> ev) { impl_->writer->write(ev); }

void RecordingWriter::label(const Label& l) {
  float j[kJointCount * 3];
  for (int i = 0; i < kJointCount; ++i)
    for (int d = 0; d < 3; ++d) j[i * 3 + d] = float(l.joints_mm[i][d]);
  impl_->label_t->append(&l.t_us);
  impl_->joints->append(j);
  impl_->valid->append(l.valid.data());
}

void RecordingWriter::mask(std::int64_t t_us, const RenderedFrame& frame) {
  impl_->mask_t->append(&t_us);
  impl_->mask->append(frame.mask.data());
}

void RecordingWriter::close() {
  Impl& m = *impl_;
  m.label_t.reset(), m.joints.reset(), m.valid.reset(), m.mask_t.reset(), m.mask.reset();
  m.labels.reset(), m.masks.reset();
  m.writer->close();
}

void run_to_end(Simulator& sim, SimSink& sink, void (*progress)(double, double, void*), void* ctx) {
  // Chunks of simulated time, so progress shows.
  const double chunk = 0.25, end = sim.duration_s();
  for (double t = sim.time_s() + chunk; sim.time_s() < end - 1e-12; t += chunk) {
    sim.run_until(std::min(t, end), sink);
    if (progress) progress(sim.time_s(), end, ctx);
  }
}

SimStats write_recording(const SimSpec& spec, const std::string& path) {
  Simulator sim(spec);
  RecordingWriter rec(path, sim);
  run_to_end(sim, rec);
  rec.close();
  return sim.stats();
}

}  // namespace yelan::camera::sim
