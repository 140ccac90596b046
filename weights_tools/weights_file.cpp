#include "weights_tools/weights_file.h"

#include "camera/io/format_error.h"
#include "camera/io/untrusted.h"

#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <system_error>

#include "camera/io/h5.h"
#include "camera/io/temp_file.h"
#include "weights_tools/parse_json.h"

namespace yelan::weights {
namespace {

namespace fs = std::filesystem;

// Owns one hid_t of any kind (camera/io's handle: one wrapper for the project).
using Id = camera::h5::H5Id;

void quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

[[noreturn]] void bad(const std::string& path, const std::string& problem) {
  throw WeightsError(path + ": " + problem);
}

Id must(hid_t id, const std::string& path, const std::string& problem) {
  if (id < 0) bad(path, problem);
  return Id(id);
}

void must(herr_t status, const std::string& path, const std::string& problem) {
  if (status < 0) bad(path, problem);
}

std::optional<std::string> string_attr(hid_t loc, const std::string& name, const std::string& path) {
  if (H5Aexists(loc, name.c_str()) <= 0) return std::nullopt;
  const std::string what = "root attribute '" + name + "'";
  Id attr = must(H5Aopen(loc, name.c_str(), H5P_DEFAULT), path, "cannot open " + what);
  Id type = must(H5Aget_type(attr.get()), path, "cannot read " + what);
  if (H5Tget_class(type.get()) != H5T_STRING) bad(path, what + " is not a string");
  Id space = must(H5Aget_space(attr.get()), path, "cannot read " + what);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) bad(path, what + " is not a single string");
  if (H5Tis_variable_str(type.get()) > 0) {
    Id mem = must(H5Tcopy(H5T_C_S1), path, "string type");
    H5Tset_size(mem.get(), H5T_VARIABLE);
    H5Tset_cset(mem.get(), H5Tget_cset(type.get()));
    char* s = nullptr;
    must(H5Aread(attr.get(), mem.get(), &s), path, "cannot read " + what);
    std::string out = s ? s : "";
    H5free_memory(s);
    return out;
  }
  const std::size_t n = H5Tget_size(type.get());
  if (n == 0 || n > (std::size_t(64) << 20)) bad(path, what + " has an absurd size");
  // One byte more than stored: a NUL-terminated memory type keeps the last character of a
  // NUL-padded string (written without a terminator) instead of cutting it.
  std::string out(n + 1, '\0');
  Id mem = must(H5Tcopy(H5T_C_S1), path, "string type");
  H5Tset_size(mem.get(), n + 1);
  must(H5Aread(attr.get(), mem.get(), out.data()), path, "cannot read " + what);
  out.resize(std::find(out.begin(), out.end(), '\0') - out.begin());
  return out;
}

std::optional<std::int64_t> int_attr(hid_t loc, const std::string& name, const std::string& path) {
  if (H5Aexists(loc, name.c_str()) <= 0) return std::nullopt;
  const std::string what = "root attribute '" + name + "'";
  Id attr = must(H5Aopen(loc, name.c_str(), H5P_DEFAULT), path, "cannot open " + what);
  Id type = must(H5Aget_type(attr.get()), path, "cannot read " + what);
  Id space = must(H5Aget_space(attr.get()), path, "cannot read " + what);
  if (H5Tget_class(type.get()) != H5T_INTEGER || H5Sget_simple_extent_npoints(space.get()) != 1)
    bad(path, what + " is not an integer");
  std::int64_t v = 0;
  must(H5Aread(attr.get(), H5T_NATIVE_INT64, &v), path, "cannot read " + what);
  return v;
}

std::vector<std::string> link_names(hid_t group, const std::string& path, const std::string& where) {
  std::vector<std::string> names;
  auto collect = [](hid_t, const char* name, const H5L_info_t*, void* out) -> herr_t {
    static_cast<std::vector<std::string>*>(out)->emplace_back(name);
    return 0;
  };
  if (H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, nullptr, collect, &names) < 0)
    bad(path, "cannot list " + where + " (corrupt file)");
  return names;
}

// True for a hard link to an object of `type` (soft and external links are refused: a
// weights file is self-contained).
bool is_hard_link_to(hid_t loc, const std::string& name, H5O_type_t type) {
  H5L_info_t link{};
  if (H5Lget_info(loc, name.c_str(), &link, H5P_DEFAULT) < 0 || link.type != H5L_TYPE_HARD) return false;
  H5O_info_t info{};
  if (H5Oget_info_by_name(loc, name.c_str(), &info, H5P_DEFAULT) < 0) return false;
  return info.type == type;
}

std::string type_text(hid_t type) {
  const std::size_t bytes = H5Tget_size(type);
  switch (H5Tget_class(type)) {
    case H5T_FLOAT: return "float" + std::to_string(8 * bytes);
    case H5T_INTEGER:
      return std::string(H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(8 * bytes);
    case H5T_STRING: return "a string";
    case H5T_COMPOUND: return "a compound type";
    default: return "a non-numeric type";
  }
}

Id untimed(hid_t plist_class, const std::string& path) {
  Id p = must(H5Pcreate(plist_class), path, "cannot create property list");
  must(H5Pset_obj_track_times(p.get(), false), path, "cannot set property list");
  return p;
}

void write_string_attr(hid_t loc, const std::string& name, const std::string& value, const std::string& path) {
  Id type = must(H5Tcopy(H5T_C_S1), path, "string type");
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  Id space = must(H5Screate(H5S_SCALAR), path, "dataspace");
  Id attr = must(H5Acreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), path,
                 "cannot write attribute " + name);
  const char* s = value.c_str();
  must(H5Awrite(attr.get(), type.get(), &s), path, "cannot write attribute " + name);
}

}  // namespace

std::string shape_text(const Shape& s) {
  std::string out = "[";
  for (std::size_t i = 0; i < s.size(); ++i) out.append(i ? ", " : "").append(std::to_string(s[i]));
  return out + "]";
}

std::int64_t element_count(const Shape& s) {
  std::int64_t n = 1;
  for (auto d : s) n *= d;
  return n;
}

bool is_parameter(const std::string& name) {
  for (const char* suffix : {".running_mean", ".running_var", ".num_batches_tracked"}) {
    const std::string sfx = suffix;
    if (name.size() >= sfx.size() && name.compare(name.size() - sfx.size(), sfx.size(), sfx) == 0) return false;
  }
  return true;
}

struct WeightsReader::File {
  Id file;
  std::map<std::string, Id> groups;
  std::uintmax_t bytes = 0;
};

WeightsReader::WeightsReader(const std::string& path) : file_(std::make_unique<File>()), path_(path) {
  quiet();
  std::error_code ec;
  if (!fs::exists(path, ec)) bad(path, "no such file");
  if (!fs::is_regular_file(path, ec)) bad(path, "not a regular file");
  file_->bytes = fs::file_size(path, ec);
  if (H5Fis_hdf5(path.c_str()) <= 0) bad(path, "not an HDF5 file");
  try {
    camera::vet_in_child(path, [&] { load_weights(path); });
  } catch (const camera::FormatError& e) {
    bad(path, e.problem());
  }
  file_->file = must(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), path,
                     "cannot open as HDF5 (truncated or corrupt)");
  const hid_t root = file_->file.get();

  auto format = string_attr(root, "format", path);
  if (!format) bad(path, "root attribute 'format' is missing (not a yelan weights file)");
  if (*format != kFormat) bad(path, "format is '" + *format + "', expected '" + kFormat + "'");
  auto version = int_attr(root, "version", path);
  if (!version) bad(path, "root attribute 'version' is missing");
  if (*version != kVersion)
    bad(path, "version " + std::to_string(*version) + " is not supported (this build reads version " +
                  std::to_string(kVersion) + ")");
  version_ = *version;
  auto config = string_attr(root, "config", path);
  if (!config) bad(path, "root attribute 'config' is missing");
  try {
    if (!parse_json(*config).is_object()) bad(path, "root attribute 'config' is not a JSON object");
  } catch (const JsonError& e) {
    bad(path, std::string("root attribute 'config' is not valid JSON: ") + e.what());
  }
  config_json_ = *config;

  const auto& wanted = group_names();
  for (const std::string& name : link_names(root, path, "the root group"))
    if (std::find(wanted.begin(), wanted.end(), name) == wanted.end())
      bad(path, "unexpected object '/" + name + "' at the root");
  for (const std::string& g : wanted) {
    if (H5Lexists(root, g.c_str(), H5P_DEFAULT) <= 0) bad(path, "group '/" + g + "' is missing");
    if (!is_hard_link_to(root, g, H5O_TYPE_GROUP)) bad(path, "'/" + g + "' is not a group");
    Id group = must(H5Gopen2(root, g.c_str(), H5P_DEFAULT), path, "cannot open group '/" + g + "'");
    auto& list = tensors_[g];
    for (const std::string& name : link_names(group.get(), path, "group '/" + g + "'")) {
      const std::string where = "/" + g + "/" + name;
      if (!is_hard_link_to(group.get(), name, H5O_TYPE_DATASET)) bad(path, where + " is not a dataset");
      Id ds = must(H5Dopen2(group.get(), name.c_str(), H5P_DEFAULT), path, "cannot open " + where);
      Id type = must(H5Dget_type(ds.get()), path, "cannot read the type of " + where);
      if (H5Tget_class(type.get()) != H5T_FLOAT || H5Tget_size(type.get()) != 4)
        bad(path, where + " is " + type_text(type.get()) + ", expected float32");
      Id space = must(H5Dget_space(ds.get()), path, "cannot read the shape of " + where);
      const int rank = H5Sget_simple_extent_ndims(space.get());
      if (rank < 0 || rank > 8 || H5Sget_simple_extent_type(space.get()) == H5S_NULL)
        bad(path, where + " has no valid shape");
      hsize_t dims[8] = {};
      H5Sget_simple_extent_dims(space.get(), dims, nullptr);
      Shape shape(dims, dims + rank);
      std::int64_t n = 1;
      for (int k = 0; k < rank; ++k) {
        const hsize_t d = dims[k];
        if (d > static_cast<hsize_t>(kMaxElements) || (n *= static_cast<std::int64_t>(d)) > kMaxElements)
          bad(path, where + " claims shape " + shape_text(shape) + ", more than 2^30 elements");
      }
      Id dcpl = must(H5Dget_create_plist(ds.get()), path, "cannot read " + where);
      if (H5Pget_layout(dcpl.get()) == H5D_CONTIGUOUS && n > 0) {
        // A contiguous tensor must lie wholly inside the file: HDF5 would read past the end.
        const haddr_t offset = H5Dget_offset(ds.get());
        const std::uintmax_t end = static_cast<std::uintmax_t>(offset) + static_cast<std::uintmax_t>(n) * 4;
        if (offset == HADDR_UNDEF) bad(path, where + " has no data stored");
        if (end > file_->bytes)
          bad(path, where + " ends at byte " + std::to_string(end) + ", past the end of the file (" +
                        std::to_string(file_->bytes) + " bytes): truncated");
      }
      list.push_back({g, name, std::move(shape)});
    }
    file_->groups.emplace(g, std::move(group));
  }
}

WeightsReader::~WeightsReader() = default;

const std::vector<TensorInfo>& WeightsReader::tensors(const std::string& group) const {
  static const std::vector<TensorInfo> none;
  auto it = tensors_.find(group);
  return it == tensors_.end() ? none : it->second;
}

const TensorInfo* WeightsReader::find(const std::string& group, const std::string& name) const {
  const auto& list = tensors(group);
  auto it = std::lower_bound(list.begin(), list.end(), name,
                             [](const TensorInfo& t, const std::string& n) { return t.name < n; });
  return it != list.end() && it->name == name ? &*it : nullptr;
}

namespace {

constexpr const char* kChecksumAttr = "fnv1a64";

// FNV-1a over a tensor's float32 bytes (little-endian, as stored): each dataset carries it,
// so a flipped byte is found on load instead of running silently. The offset basis is one
// digit short of FNV's published 14695981039346656037; every file written so far carries
// this one, so it stays (weights_tools/h5weights.py computes the same).
std::uint64_t tensor_checksum(const std::vector<float>& v) {
  std::uint64_t h = 1469598103934665603ull;
  const auto* b = reinterpret_cast<const unsigned char*>(v.data());
  for (std::size_t i = 0; i < v.size() * sizeof(float); ++i) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

}  // namespace

std::vector<float> WeightsReader::read(const TensorInfo& t) const {
  const std::string where = "/" + t.group + "/" + t.name;
  std::vector<float> data(static_cast<std::size_t>(element_count(t.shape)));
  Id ds = must(H5Dopen2(file_->groups.at(t.group).get(), t.name.c_str(), H5P_DEFAULT), path_,
               "cannot open " + where);
  if (!data.empty())
    must(H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()), path_,
         "cannot read " + where + " (truncated or corrupt data)");
  if (H5Aexists(ds.get(), kChecksumAttr) > 0) {  // files written before checksums have none
    Id attr = must(H5Aopen(ds.get(), kChecksumAttr, H5P_DEFAULT), path_, "cannot open the checksum of " + where);
    std::uint64_t stored = 0;
    must(H5Aread(attr.get(), H5T_NATIVE_UINT64, &stored), path_, "cannot read the checksum of " + where);
    if (stored != tensor_checksum(data))
      bad(path_, "tensor " + where + ": checksum mismatch (its bytes changed since the file was written)");
  }
  return data;
}

Weights load_weights(const std::string& path) {
  WeightsReader r(path);
  Weights w;
  w.config_json = r.config_json();
  for (const std::string& g : group_names()) {
    auto& group = w.groups[g];
    for (const TensorInfo& t : r.tensors(g)) group[t.name] = Tensor{t.shape, r.read(t)};
  }
  return w;
}

void save_weights(const std::string& path, const Weights& w) {
  quiet();
  for (const auto& [g, tensors] : w.groups) {
    const auto& wanted = group_names();
    if (std::find(wanted.begin(), wanted.end(), g) == wanted.end())
      throw std::invalid_argument("weights group '" + g + "' is neither mask nor pose");
    for (const auto& [name, t] : tensors)
      if (element_count(t.shape) != static_cast<std::int64_t>(t.data.size()) || name.empty() ||
          name.find('/') != std::string::npos)
        throw std::invalid_argument("weights tensor '" + g + "/" + name + "': bad name or " +
                                    std::to_string(t.data.size()) + " values for shape " + shape_text(t.shape));
  }
  const auto tmp_file = [&] {
    try {
      return std::make_unique<camera::TempFile>(path);
    } catch (const std::runtime_error& e) {
      throw WeightsError(e.what());
    }
  }();
  const std::string& tmp = tmp_file->path();
  {
    {
      Id fcpl = untimed(H5P_FILE_CREATE, tmp);
      Id file = must(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, fcpl.get(), H5P_DEFAULT), tmp, "cannot create file");
      const hid_t root = file.get();
      write_string_attr(root, "format", kFormat, tmp);
      {
        Id space = must(H5Screate(H5S_SCALAR), tmp, "dataspace");
        Id attr = must(H5Acreate2(root, "version", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), tmp,
                       "cannot write attribute version");
        const std::int64_t v = kVersion;
        must(H5Awrite(attr.get(), H5T_NATIVE_INT64, &v), tmp, "cannot write attribute version");
      }
      write_string_attr(root, "config", w.config_json, tmp);
      Id gcpl = untimed(H5P_GROUP_CREATE, tmp);
      Id dcpl = untimed(H5P_DATASET_CREATE, tmp);
      for (const std::string& g : group_names()) {
        Id group = must(H5Gcreate2(root, g.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), tmp,
                        "cannot create group " + g);
        auto it = w.groups.find(g);
        if (it == w.groups.end()) continue;
        for (const auto& [name, t] : it->second) {
          std::vector<hsize_t> dims(t.shape.begin(), t.shape.end());
          Id space = must(t.shape.empty() ? H5Screate(H5S_SCALAR)
                                          : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                          tmp, "dataspace of " + name);
          Id ds = must(H5Dcreate2(group.get(), name.c_str(), H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, dcpl.get(),
                                  H5P_DEFAULT),
                       tmp, "cannot create dataset " + g + "/" + name);
          if (!t.data.empty())
            must(H5Dwrite(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, t.data.data()), tmp,
                 "cannot write dataset " + g + "/" + name);
          Id cspace = must(H5Screate(H5S_SCALAR), tmp, "dataspace");
          Id cattr = must(H5Acreate2(ds.get(), kChecksumAttr, H5T_STD_U64LE, cspace.get(), H5P_DEFAULT, H5P_DEFAULT), tmp,
                          "cannot write the checksum of " + g + "/" + name);
          const std::uint64_t sum = tensor_checksum(t.data);
          must(H5Awrite(cattr.get(), H5T_NATIVE_UINT64, &sum), tmp, "cannot write the checksum of " + g + "/" + name);
        }
      }
      must(H5Fflush(root, H5F_SCOPE_GLOBAL), tmp, "cannot flush");
    }
  }
  try {
    tmp_file->commit();
  } catch (const std::runtime_error& e) {
    throw WeightsError(e.what());
  }
}

}  // namespace yelan::weights
