#include "camera/io/h5.h"

#include <cstdint>

namespace yelan::camera::h5 {

void H5Id::reset() noexcept {
  if (id_ >= 0) {
    switch (H5Iget_type(id_)) {
      case H5I_FILE: H5Fclose(id_); break;
      case H5I_GROUP: H5Gclose(id_); break;
      case H5I_DATASET: H5Dclose(id_); break;
      case H5I_DATASPACE: H5Sclose(id_); break;
      case H5I_DATATYPE: H5Tclose(id_); break;
      case H5I_ATTR: H5Aclose(id_); break;
      case H5I_GENPROP_LST: H5Pclose(id_); break;
      default: H5Idec_ref(id_); break;
    }
  }
  id_ = H5I_INVALID_HID;
}

H5Id check(hid_t id, const std::string& what) {
  if (id < 0) throw H5Failure(what);
  return H5Id(id);
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw H5Failure(what);
}

void silence_errors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

H5Id open_file(const std::string& path) {
  silence_errors();
  return check(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "cannot open as HDF5");
}

H5Id create_file(const std::string& path) {
  silence_errors();
  // No time stamp on the root group either: equal content, equal bytes.
  H5Id fcpl = check(H5Pcreate(H5P_FILE_CREATE), "file properties");
  check(H5Pset_obj_track_times(fcpl.get(), false), "file properties");
  return check(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), "cannot create " + path);
}

bool exists(hid_t loc, const std::string& path) {
  std::string sofar;
  std::size_t at = 0;
  while (at <= path.size()) {
    std::size_t slash = path.find('/', at);
    sofar = path.substr(0, slash);
    if (!sofar.empty() && H5Lexists(loc, sofar.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) break;
    at = slash + 1;
  }
  return true;
}

H5Id create_group(hid_t loc, const std::string& name) {
  H5Id props = check(H5Pcreate(H5P_GROUP_CREATE), "group properties");
  check(H5Pset_obj_track_times(props.get(), false), "group properties");
  return check(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, props.get(), H5P_DEFAULT), "cannot create group " + name);
}

H5Id untimed_dataset_props() {
  H5Id props = check(H5Pcreate(H5P_DATASET_CREATE), "dataset properties");
  check(H5Pset_obj_track_times(props.get(), false), "dataset properties");
  return props;
}

H5Id create_growing_1d(hid_t loc, const std::string& name, hid_t type, hsize_t chunk) {
  hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED};
  H5Id space = check(H5Screate_simple(1, dims, maxdims), "dataspace");
  H5Id props = untimed_dataset_props();
  check(H5Pset_chunk(props.get(), 1, &chunk), "chunking");
  check(H5Pset_shuffle(props.get()), "shuffle filter");
  check(H5Pset_deflate(props.get(), 4), "deflate filter");
  return check(H5Dcreate2(loc, name.c_str(), type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
               "cannot create dataset " + name);
}

void append_1d(hid_t dataset, hid_t mem_type, const void* data, hsize_t n) {
  if (n == 0) return;
  const hsize_t old = shape(dataset).at(0);
  hsize_t grown[1] = {old + n};
  check(H5Dset_extent(dataset, grown), "cannot grow dataset");
  H5Id file_space = check(H5Dget_space(dataset), "dataspace");
  hsize_t start[1] = {old}, count[1] = {n};
  check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "selection");
  H5Id mem_space = check(H5Screate_simple(1, count, nullptr), "dataspace");
  check(H5Dwrite(dataset, mem_type, mem_space.get(), file_space.get(), H5P_DEFAULT, data), "cannot write dataset");
}

std::uint64_t chunk_bytes(hid_t dataset) {
  H5Id dcpl = check(H5Dget_create_plist(dataset), "dataset properties");
  if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED) return 0;
  hsize_t dims[8] = {};
  const int rank = H5Pget_chunk(dcpl.get(), 8, dims);
  if (rank < 0 || rank > 8) throw H5Failure("bad chunk rank");
  H5Id type = check(H5Dget_type(dataset), "dataset type");
  long double bytes = static_cast<long double>(H5Tget_size(type.get()));
  for (int i = 0; i < rank; ++i) bytes *= static_cast<long double>(dims[i]);
  return bytes > 1e18L ? UINT64_MAX : static_cast<std::uint64_t>(bytes);
}

bool holds_small_numbers(hid_t dataset, bool integers_only) {
  H5Id type = check(H5Dget_type(dataset), "dataset type");
  const H5T_class_t cls = H5Tget_class(type.get());
  const std::size_t bytes = H5Tget_size(type.get());
  return (cls == H5T_INTEGER || (!integers_only && cls == H5T_FLOAT)) && bytes > 0 && bytes <= 8;
}

void require_numeric(hid_t dataset, const std::string& name) {
  if (!holds_small_numbers(dataset)) throw H5Failure(name + " is not a dataset of numbers of at most 8 bytes");
}

void check_stored_chunks(hid_t dataset, hsize_t first, hsize_t n, std::uint64_t file_size,
                         std::uint64_t max_bytes) {
  H5Id dcpl = check(H5Dget_create_plist(dataset), "dataset properties");
  if (H5Pget_layout(dcpl.get()) != H5D_CHUNKED || n == 0) return;
  hsize_t dims[8] = {};
  const int rank = H5Pget_chunk(dcpl.get(), 8, dims);
  if (rank < 1 || rank > 8 || dims[0] == 0) throw H5Failure("bad chunk shape");
  const auto full = shape(dataset);
  if (full.size() != static_cast<std::size_t>(rank)) throw H5Failure("chunk rank differs from dataset rank");
  // Filters that cannot make a chunk larger (shuffle, the checksum): libhdf5 copies a whole
  // chunk's bytes out of what such a pipeline returns without checking its length, so a chunk
  // stored smaller than its shape is read past its end (fuzz_recording found a pipeline cut
  // down to shuffle alone). Bit i of `keeps_size` says filter i cannot expand its input.
  const int nfilters = H5Pget_nfilters(dcpl.get());
  if (nfilters < 0 || nfilters > 32) throw H5Failure("bad filter pipeline");
  unsigned keeps_size = 0;
  for (int i = 0; i < nfilters; ++i) {
    unsigned flags = 0, config = 0;
    std::size_t nvalues = 0;
    const H5Z_filter_t id = H5Pget_filter2(dcpl.get(), static_cast<unsigned>(i), &flags, &nvalues, nullptr, 0, nullptr, &config);
    if (id == H5Z_FILTER_SHUFFLE || id == H5Z_FILTER_FLETCHER32) keeps_size |= 1u << i;
  }
  const std::uint64_t whole = chunk_bytes(dataset);
  hsize_t coord[8] = {};
  for (hsize_t row = first / dims[0] * dims[0]; row < first + n; row += dims[0]) {
    coord[0] = row;
    // Every chunk across the other dimensions (v2e's N x 4 may be chunked by column).
    for (hsize_t col = 0; col < (rank > 1 ? full[1] : 1); col += (rank > 1 ? dims[1] : 1)) {
      if (rank > 1) coord[1] = col;
      unsigned mask = 0;
      haddr_t addr = HADDR_UNDEF;
      hsize_t bytes = 0;
      if (H5Dget_chunk_info_by_coord(dataset, coord, &mask, &addr, &bytes) < 0) throw H5Failure("bad chunk index");
      if (addr == HADDR_UNDEF) continue;  // never written: reads as the fill value
      if (bytes > max_bytes || addr > file_size || bytes > file_size - addr)
        throw H5Failure("chunk at row " + std::to_string(row) + " claims " + std::to_string(bytes) +
                        " bytes at address " + std::to_string(addr) + " of a " + std::to_string(file_size) +
                        "-byte file");
      const unsigned applied = ~mask & ((nfilters == 32 ? 0u : 1u << nfilters) - 1u);  // filters not skipped
      if ((applied & ~keeps_size) == 0 && bytes < whole)
        throw H5Failure("chunk at row " + std::to_string(row) + " stores " + std::to_string(bytes) + " bytes where its " +
                        "shape needs " + std::to_string(whole) + " and its filters cannot expand it");
      if (rank > 2) break;
    }
  }
}

std::vector<hsize_t> shape(hid_t dataset) {
  H5Id space = check(H5Dget_space(dataset), "dataspace");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0 || rank > 8) throw H5Failure("bad dataset rank");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

void read_rows(hid_t dataset, hid_t mem_type, hsize_t first, hsize_t n, void* out, int col) {
  if (n == 0) return;
  H5Id file_space = check(H5Dget_space(dataset), "dataspace");
  if (col < 0) {
    hsize_t start[1] = {first}, count[1] = {n};
    check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "selection");
  } else {
    hsize_t start[2] = {first, static_cast<hsize_t>(col)}, count[2] = {n, 1};
    check(H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "selection");
  }
  hsize_t mem_count[1] = {n};
  H5Id mem_space = check(H5Screate_simple(1, mem_count, nullptr), "dataspace");
  check(H5Dread(dataset, mem_type, mem_space.get(), file_space.get(), H5P_DEFAULT, out), "cannot read dataset");
}

void write_attr_string(hid_t loc, const std::string& name, const std::string& value) {
  H5Id type = check(H5Tcopy(H5T_C_S1), "string type");
  check(H5Tset_size(type.get(), value.empty() ? 1 : value.size()), "string type");
  check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), "string type");
  H5Id space = check(H5Screate(H5S_SCALAR), "dataspace");
  H5Id attr = check(H5Acreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                    "cannot create attribute " + name);
  check(H5Awrite(attr.get(), type.get(), value.data()), "cannot write attribute " + name);
}

void write_attr_i64(hid_t loc, const std::string& name, std::int64_t value) {
  H5Id space = check(H5Screate(H5S_SCALAR), "dataspace");
  H5Id attr = check(H5Acreate2(loc, name.c_str(), H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                    "cannot create attribute " + name);
  check(H5Awrite(attr.get(), H5T_NATIVE_INT64, &value), "cannot write attribute " + name);
}

std::optional<std::string> read_attr_string(hid_t loc, const std::string& name) {
  if (H5Aexists(loc, name.c_str()) <= 0) return std::nullopt;
  H5Id attr = check(H5Aopen(loc, name.c_str(), H5P_DEFAULT), "attribute " + name);
  H5Id type = check(H5Aget_type(attr.get()), "attribute type");
  if (H5Tget_class(type.get()) != H5T_STRING) return std::nullopt;
  H5Id space = check(H5Aget_space(attr.get()), "attribute space");
  if (H5Sget_simple_extent_npoints(space.get()) != 1) return std::nullopt;
  if (H5Tis_variable_str(type.get()) > 0) {
    char* s = nullptr;
    H5Id mem = check(H5Tcopy(H5T_C_S1), "string type");
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));  // h5py writes UTF-8: the memory type must agree
    check(H5Aread(attr.get(), mem.get(), &s), "cannot read attribute " + name);
    std::string v = s ? s : "";
    H5free_memory(s);
    return v;
  }
  const std::size_t n = H5Tget_size(type.get());
  if (n == 0 || n > (1 << 20)) return std::nullopt;
  std::string v(n, '\0');
  check(H5Aread(attr.get(), type.get(), v.data()), "cannot read attribute " + name);
  v.resize(v.find('\0') == std::string::npos ? v.size() : v.find('\0'));
  return v;
}

std::optional<std::int64_t> read_attr_i64(hid_t loc, const std::string& name) {
  if (H5Aexists(loc, name.c_str()) <= 0) return std::nullopt;
  H5Id attr = check(H5Aopen(loc, name.c_str(), H5P_DEFAULT), "attribute " + name);
  H5Id type = check(H5Aget_type(attr.get()), "attribute type");
  const H5T_class_t cls = H5Tget_class(type.get());
  if ((cls != H5T_INTEGER && cls != H5T_FLOAT) || H5Tget_size(type.get()) > 8) return std::nullopt;
  H5Id space = check(H5Aget_space(attr.get()), "attribute space");
  if (H5Sget_simple_extent_npoints(space.get()) != 1) return std::nullopt;
  std::int64_t v = 0;
  check(H5Aread(attr.get(), H5T_NATIVE_INT64, &v), "cannot read attribute " + name);
  return v;
}

std::optional<std::int64_t> read_scalar_i64(hid_t loc, const std::string& name) {
  if (!exists(loc, name)) return std::nullopt;
  H5Id ds = check(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), "dataset " + name);
  require_numeric(ds.get(), name);
  H5Id space = check(H5Dget_space(ds.get()), "dataspace");
  if (H5Sget_simple_extent_npoints(space.get()) != 1) return std::nullopt;
  std::int64_t v = 0;
  check(H5Dread(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), "cannot read " + name);
  return v;
}

}  // namespace yelan::camera::h5
