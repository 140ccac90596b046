#include "camera/repr/volume_file.h"

#include <hdf5.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace yelan::camera {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": cannot write HDF5 volumes: " + what);
}

// HDF5's default error handler prints a stack to stderr; our own message says enough.
struct QuietHdf5 {
  H5E_auto2_t func = nullptr;
  void* data = nullptr;
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func, data); }
};

void write_string_attr(hid_t obj, const char* name, const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size() + 1);
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = attr < 0 ? -1 : H5Awrite(attr, type, value.c_str());
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
  if (rc < 0) throw std::runtime_error(std::string("attribute ") + name);
}

void write_int_attr(hid_t obj, const char* name, std::int64_t value) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t attr = H5Acreate2(obj, name, H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t rc = attr < 0 ? -1 : H5Awrite(attr, H5T_NATIVE_INT64, &value);
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  if (rc < 0) throw std::runtime_error(std::string("attribute ") + name);
}

hid_t create_extendable(hid_t file, const char* name, hid_t type, int rank, const hsize_t* dims_one) {
  hsize_t dims[4], maxdims[4];
  for (int i = 0; i < rank; ++i) dims[i] = maxdims[i] = dims_one[i];
  dims[0] = 0;
  maxdims[0] = H5S_UNLIMITED;
  hid_t space = H5Screate_simple(rank, dims, maxdims);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  hsize_t chunk[4];
  for (int i = 0; i < rank; ++i) chunk[i] = dims_one[i];
  if (rank == 1) chunk[0] = 1024;  // timestamps: many per chunk
  H5Pset_chunk(dcpl, rank, chunk);
  if (rank > 1) H5Pset_deflate(dcpl, 1);
  hid_t ds = H5Dcreate2(file, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  H5Pclose(dcpl);
  H5Sclose(space);
  return ds;
}

void append_rows(hid_t ds, int rank, const hsize_t* row_dims, std::int64_t at, hid_t mem_type,
                 const void* data) {
  hsize_t dims[4], start[4] = {0, 0, 0, 0};
  for (int i = 0; i < rank; ++i) dims[i] = row_dims[i];
  dims[0] = hsize_t(at) + 1;
  if (H5Dset_extent(ds, dims) < 0) throw std::runtime_error("extend");
  hid_t file_space = H5Dget_space(ds);
  start[0] = hsize_t(at);
  hsize_t count[4];
  for (int i = 0; i < rank; ++i) count[i] = row_dims[i];
  count[0] = 1;
  H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr);
  hid_t mem_space = H5Screate_simple(rank, count, nullptr);
  herr_t rc = H5Dwrite(ds, mem_type, mem_space, file_space, H5P_DEFAULT, data);
  H5Sclose(mem_space);
  H5Sclose(file_space);
  if (rc < 0) throw std::runtime_error("write");
}

}  // namespace

VolumeFileWriter::VolumeFileWriter(std::string path, std::string type, int channels, int height,
                                   int width,
                                   const std::vector<std::pair<std::string, std::int64_t>>& int_attrs)
    : path_(std::move(path)), channels_(channels), height_(height), width_(width) {
  if (channels <= 0 || height <= 0 || width <= 0) fail(path_, "empty volume shape");
  tmp_ = std::make_unique<TempFile>(path_);
  tmp_path_ = tmp_->path();
  QuietHdf5 quiet;
  file_ = H5Fcreate(tmp_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) fail(path_, "cannot create " + tmp_path_);
  try {
    const hsize_t vol_dims[4] = {1, hsize_t(channels), hsize_t(height), hsize_t(width)};
    volumes_ = create_extendable(file_, "volumes", H5T_IEEE_F32LE, 4, vol_dims);
    const hsize_t t_dims[1] = {1};
    times_ = create_extendable(file_, "t", H5T_STD_I64LE, 1, t_dims);
    if (volumes_ < 0 || times_ < 0) throw std::runtime_error("datasets");
    write_string_attr(file_, "format", "yelan-repr");
    write_string_attr(file_, "type", type);
    for (const auto& [name, value] : int_attrs) write_int_attr(file_, name.c_str(), value);
  } catch (const std::exception& e) {
    close_handles();
    fail(path_, e.what());
  }
}

void VolumeFileWriter::append(std::int64_t t_us, const float* volume) {
  if (finished_) fail(path_, "append after finish");
  QuietHdf5 quiet;
  try {
    const hsize_t vol_dims[4] = {1, hsize_t(channels_), hsize_t(height_), hsize_t(width_)};
    append_rows(volumes_, 4, vol_dims, count_, H5T_NATIVE_FLOAT, volume);
    const hsize_t t_dims[1] = {1};
    append_rows(times_, 1, t_dims, count_, H5T_NATIVE_INT64, &t_us);
  } catch (const std::exception& e) {
    fail(tmp_path_, std::string("volume ") + std::to_string(count_) + ": " + e.what());
  }
  ++count_;
}

void VolumeFileWriter::finish() {
  if (finished_) return;
  QuietHdf5 quiet;
  const bool flushed = H5Fflush(file_, H5F_SCOPE_GLOBAL) >= 0;
  close_handles();
  if (!flushed) fail(tmp_path_, "flush failed");
  try {
    tmp_->commit();
  } catch (const std::exception& e) {
    fail(path_, e.what());
  }
  finished_ = true;
}

void VolumeFileWriter::close_handles() noexcept {
  if (volumes_ >= 0) H5Dclose(volumes_);
  if (times_ >= 0) H5Dclose(times_);
  if (file_ >= 0) H5Fclose(file_);
  volumes_ = times_ = file_ = -1;
}

VolumeFileWriter::~VolumeFileWriter() {
  if (finished_) return;
  QuietHdf5 quiet;
  close_handles();  // the TempFile removes the file
}

}  // namespace yelan::camera
