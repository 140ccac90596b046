// Events in HDF5: our recordings (`/events/{t,x,y,p}`, `/events/ms_to_idx`, root attributes
// format="yelan-recording", version, width, height), DSEC (`events/{x,y,p,t}` with
// `t_offset` and `ms_to_idx` at the root) and v2e (`events`, N x 4: t, x, y, p).
// Read in row blocks, so memory stays bounded whatever the file size.
#include <algorithm>
#include <array>
#include <climits>
#include <cstring>
#include <filesystem>
#include <type_traits>

#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "camera/io/h5_chunks.h"
#include "camera/io/readers.h"

namespace yelan::camera {
namespace {

constexpr hsize_t kRowsPerRead = 1 << 16;
// HDF5 holds a whole chunk in memory to read from it; ours are 64Ki rows (512 KiB).
constexpr std::uint64_t kMaxChunkBytes = 64u << 20;
constexpr int kOurVersion = 1;
// ms_to_idx holds one entry per millisecond: 100 M entries (800 MB) is 27.8 hours.
constexpr std::int64_t kMaxIndexedSpanUs = 100'000'000'000LL;

// Elements of a little-endian integer column as int64, as H5Dread converts them (an unsigned
// value past INT64_MAX saturates).
void widen(const unsigned char* raw, std::size_t size, bool is_signed, std::size_t n, std::int64_t* out) {
  auto each = [&](auto type_tag) {
    using T = decltype(type_tag);
    for (std::size_t i = 0; i < n; ++i) {
      T v;
      std::memcpy(&v, raw + i * sizeof(T), sizeof(T));
      if constexpr (std::is_same_v<T, std::uint64_t>)
        out[i] = v > std::uint64_t(INT64_MAX) ? INT64_MAX : std::int64_t(v);
      else
        out[i] = std::int64_t(v);
    }
  };
  switch (size * 2 + (is_signed ? 1 : 0)) {
    case 2: return each(std::uint8_t{});
    case 3: return each(std::int8_t{});
    case 4: return each(std::uint16_t{});
    case 5: return each(std::int16_t{});
    case 8: return each(std::uint32_t{});
    case 9: return each(std::int32_t{});
    case 16: return each(std::uint64_t{});
    default: return each(std::int64_t{});
  }
}

class Hdf5Reader final : public EventReader {
 public:
  explicit Hdf5Reader(const std::string& path) : EventReader(path) {
    try {
      file_ = h5::open_file(path);
    } catch (const h5::H5Failure&) {
      throw FormatError(path, 0, "not a readable HDF5 file");
    }
    size_ = std::filesystem::file_size(path);
    try {
      classify();
    } catch (const h5::H5Failure& e) {
      throw FormatError(path, 0, std::string("HDF5: ") + e.what());
    }
  }
  std::uint64_t position() const override {
    return rows_ ? static_cast<std::uint64_t>(static_cast<double>(next_) / static_cast<double>(rows_) *
                                              static_cast<double>(size_))
                 : size_;
  }
  std::uint64_t file_size() const override { return size_; }
  bool fast_seek() const override { return ms_to_idx_.valid(); }

 protected:
  void restart() override { next_ = 0; }

  bool decode(std::vector<Event>& out) override {
    if (next_ >= rows_) return false;
    hsize_t n = std::min(kRowsPerRead, rows_ - next_);
    if (!raw_.empty()) n = std::min(n, raw_rows_ - next_ % raw_rows_);  // within one chunk
    for (auto& c : cols_) c.resize(n);
    try {
      for (int k = 0; k < (matrix_.valid() ? 1 : 4); ++k)
        if (raw_.empty() || raw_[static_cast<std::size_t>(k)].cached != next_ / raw_rows_)  // a kept chunk was checked
          h5::check_stored_chunks(column_ds(k), next_, n, size_, kMaxChunkBytes);
      for (int k = 0; k < 4; ++k)
        if (raw_.empty() || !read_raw(k, n))
          h5::read_rows(column_ds(k), H5T_NATIVE_INT64, next_, n, cols_[static_cast<std::size_t>(k)].data(),
                        matrix_.valid() ? matrix_col_[static_cast<std::size_t>(k)] : -1);
    } catch (const h5::H5Failure& e) {
      throw FormatError(path_, 0, "rows " + std::to_string(next_) + ".." + std::to_string(next_ + n) +
                                      ": " + e.what() + " (corrupt chunk?)");
    }
    std::uint64_t bad = 0;
    for (hsize_t i = 0; i < n; ++i) {
      const std::int64_t x = cols_[1][i], y = cols_[2][i];
      if (x < 0 || y < 0 || x > 65535 || y > 65535) {
        ++bad;
        continue;
      }
      out.push_back({offset_time(cols_[0][i], next_ + i), static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y),
                     static_cast<std::uint8_t>(cols_[3][i] > 0)});
    }
    warn_skipped(0, "rows from " + std::to_string(next_) + " hold coordinates outside 0..65535 (dropped)", bad);
    next_ += n;
    return next_ < rows_;
  }

  bool seek_index(std::int64_t t) override {
    if (!ms_to_idx_.valid()) return false;
    // t - ms_origin_ past INT64_MAX (an origin near INT64_MIN in a hostile file) lies past the end.
    std::int64_t since = 0;
    const bool past_end = t >= ms_origin_ && __builtin_sub_overflow(t, ms_origin_, &since);
    const std::int64_t k = t < ms_origin_ ? 0 : since / 1000;
    if (past_end || k >= static_cast<std::int64_t>(ms_len_)) {
      next_ = rows_;
      return true;
    }
    std::uint64_t idx = 0;
    try {
      h5::check_stored_chunks(ms_to_idx_.get(), static_cast<hsize_t>(k), 1, size_, kMaxChunkBytes);
      h5::read_rows(ms_to_idx_.get(), H5T_NATIVE_UINT64, static_cast<hsize_t>(k), 1, &idx);
    } catch (const h5::H5Failure&) {
      return false;
    }
    next_ = std::min<hsize_t>(idx, rows_);
    return true;
  }

 private:
  hid_t column_ds(int k) const { return matrix_.valid() ? matrix_.get() : columns_[static_cast<std::size_t>(k)].get(); }

  // Rows [next_, next_ + n) of column k (inside one chunk) from its chunk inflated here, the
  // chunk kept for the next rows; false where the chunk was never written.
  bool read_raw(int k, hsize_t n) {
    RawColumn& c = raw_[static_cast<std::size_t>(k)];
    const hsize_t chunk = next_ / raw_rows_;
    if (c.cached != chunk) {
      const hsize_t coord = chunk * raw_rows_;
      c.cached = ~hsize_t(0);
      if (!c.reader.read(column_ds(k), &coord, c.bytes)) return false;
      c.cached = chunk;
    }
    const std::size_t size = c.reader.element_bytes();
    widen(c.bytes.data() + (next_ - chunk * raw_rows_) * size, size, c.is_signed, n,
          cols_[static_cast<std::size_t>(k)].data());
    return true;
  }

  // The four columns through RawChunkReader where each suits it and all share one chunk length.
  void use_raw_chunks() {
    std::vector<RawColumn> raw;
    for (int k = 0; k < 4; ++k) {
      const hid_t ds = column_ds(k);
      if (!h5::RawChunkReader::suits(ds)) return;
      h5::H5Id type = h5::check(H5Dget_type(ds), "column type");
      raw.push_back({h5::RawChunkReader(ds), H5Tget_sign(type.get()) == H5T_SGN_2, ~hsize_t(0), {}});
      if (raw.back().reader.chunk().size() != 1 || raw.back().reader.chunk()[0] != raw[0].reader.chunk()[0]) return;
    }
    raw_rows_ = raw[0].reader.chunk()[0];
    raw_ = std::move(raw);
  }

  void classify() {
    const hid_t f = file_.get();
    const auto fmt = h5::read_attr_string(f, "format");
    if (fmt && *fmt == "yelan-recording") {
      info_.format = "yelan-h5";
      if (auto w = h5::read_attr_i64(f, "width")) info_.width = static_cast<int>(std::clamp<std::int64_t>(*w, 0, 65536));
      if (auto h = h5::read_attr_i64(f, "height")) info_.height = static_cast<int>(std::clamp<std::int64_t>(*h, 0, 65536));
      // SPEC 2 puts the sensor size in /camera; our writer adds the root attributes, other
      // writers need not.
      if (info_.width == 0 && h5::exists(f, "camera/width"))
        if (auto w = h5::read_scalar_i64(f, "camera/width")) info_.width = static_cast<int>(std::clamp<std::int64_t>(*w, 0, 65536));
      if (info_.height == 0 && h5::exists(f, "camera/height"))
        if (auto h = h5::read_scalar_i64(f, "camera/height")) info_.height = static_cast<int>(std::clamp<std::int64_t>(*h, 0, 65536));
      open_columns("events");
      open_ms_index("events/ms_to_idx");
      if (ms_to_idx_.valid()) {
        ms_origin_ = h5::read_attr_i64(ms_to_idx_.get(), "t0_us").value_or(0);
      }
    } else if (h5::exists(f, "events/x") && h5::exists(f, "events/t")) {
      info_.format = "dsec-h5";
      open_columns("events");
      t_offset_ = h5::read_scalar_i64(f, "t_offset").value_or(0);
      open_ms_index("ms_to_idx");
      ms_origin_ = t_offset_;
    } else if (h5::exists(f, "events")) {
      info_.format = "v2e-h5";
      H5O_info_t oi;
      if (H5Oget_info_by_name(f, "events", &oi, H5P_DEFAULT) < 0 || oi.type != H5O_TYPE_DATASET)
        throw FormatError(path_, 0, "HDF5 file has an `events` group without x/y/p/t datasets");
      matrix_ = h5::check(H5Dopen2(f, "events", H5P_DEFAULT), "dataset events");
      check_chunks(matrix_.get(), "events");
      const auto dims = h5::shape(matrix_.get());
      if (dims.size() != 2 || dims[1] != 4)
        throw FormatError(path_, 0, "v2e `events` must be N x 4 (t, x, y, p)");
      rows_ = dims[0];
    } else {
      throw FormatError(path_, 0, "HDF5 file holds no events (no /events datasets)");
    }
    info_.events = rows_;
    if (rows_ > 0) {
      h5::check_stored_chunks(column_ds(0), 0, 1, size_, kMaxChunkBytes);
      std::int64_t t0 = 0;
      h5::read_rows(column_ds(0), H5T_NATIVE_INT64, 0, 1, &t0, matrix_.valid() ? 0 : -1);
      info_.t_first = offset_time(t0, 0);
    }
  }

  // A row's time plus t_offset (DSEC), checked: the sum of two values near INT64_MAX would
  // wrap (undefined behaviour) before the base class could refuse the timestamp.
  std::int64_t offset_time(std::int64_t t, hsize_t row) const {
    std::int64_t sum = 0;
    if (__builtin_add_overflow(t, t_offset_, &sum))
      throw FormatError(path_, position(), "row " + std::to_string(row) + ": t " + std::to_string(t) + " + t_offset " +
                                               std::to_string(t_offset_) + " overflows 64 bits");
    return sum;
  }

  void check_chunks(hid_t ds, const std::string& name) {
    const std::uint64_t bytes = h5::chunk_bytes(ds);
    if (bytes > kMaxChunkBytes)
      throw FormatError(path_, 0, "/" + name + " claims chunks of " + std::to_string(bytes) +
                                      " bytes (more than 64 MiB: corrupt?)");
  }

  void open_columns(const std::string& group) {
    static const char* names[4] = {"t", "x", "y", "p"};
    for (int k = 0; k < 4; ++k) {
      const std::string name = group + "/" + names[k];
      if (!h5::exists(file_.get(), name)) throw FormatError(path_, 0, "HDF5 file lacks dataset /" + name);
      auto& ds = columns_[static_cast<std::size_t>(k)];
      ds = h5::check(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), "dataset " + name);
      check_chunks(ds.get(), name);
      if (!h5::holds_small_numbers(ds.get(), true))
        throw FormatError(path_, 0, "/" + name + " is not a dataset of integers of at most 8 bytes");
      const auto dims = h5::shape(ds.get());
      if (dims.size() != 1) throw FormatError(path_, 0, "/" + name + " is not one-dimensional");
      if (k == 0) rows_ = dims[0];
      else if (dims[0] != rows_)
        throw FormatError(path_, 0, "/" + name + " has " + std::to_string(dims[0]) + " rows but /" + group +
                                        "/t has " + std::to_string(rows_));
    }
    use_raw_chunks();
  }

  void open_ms_index(const std::string& name) {
    if (!h5::exists(file_.get(), name)) return;
    ms_to_idx_ = h5::check(H5Dopen2(file_.get(), name.c_str(), H5P_DEFAULT), "dataset " + name);
    check_chunks(ms_to_idx_.get(), name);
    const auto dims = h5::shape(ms_to_idx_.get());
    if (dims.size() != 1 || !h5::holds_small_numbers(ms_to_idx_.get(), true)) {
      ms_to_idx_.reset();
      return;
    }
    ms_len_ = dims[0];
  }

  using H5Id = h5::H5Id;
  H5Id file_, matrix_, ms_to_idx_;
  std::array<H5Id, 4> columns_;
  std::array<int, 4> matrix_col_{0, 1, 2, 3};
  std::array<std::vector<std::int64_t>, 4> cols_;
  struct RawColumn {
    h5::RawChunkReader reader;
    bool is_signed = false;
    hsize_t cached = ~hsize_t(0);  // the chunk held in bytes
    std::vector<unsigned char> bytes;
  };
  std::vector<RawColumn> raw_;  // empty: the columns go through H5Dread
  hsize_t raw_rows_ = 0;
  hsize_t rows_ = 0, next_ = 0, ms_len_ = 0;
  std::int64_t t_offset_ = 0, ms_origin_ = 0;
  std::uint64_t size_ = 0;
};

// Streams events into extendible datasets; ms_to_idx[k] is the index of the first event at
// or after t0_us + 1000 k, with one final entry equal to the event count.
class YelanH5Writer final : public EventWriter {
 public:
  YelanH5Writer(const std::string& path, const StreamInfo& info) : tmp_(path) {
    file_ = h5::create_file(tmp_.path());
    const hid_t f = file_.get();
    h5::write_attr_string(f, "format", "yelan-recording");
    h5::write_attr_i64(f, "version", kOurVersion);
    h5::write_attr_i64(f, "width", info.width);
    h5::write_attr_i64(f, "height", info.height);
    events_ = h5::create_group(f, "events");
    const hsize_t chunk = 1 << 16;
    t_ = h5::create_growing_1d(events_.get(), "t", H5T_STD_I64LE, chunk);
    x_ = h5::create_growing_1d(events_.get(), "x", H5T_STD_U16LE, chunk);
    y_ = h5::create_growing_1d(events_.get(), "y", H5T_STD_U16LE, chunk);
    p_ = h5::create_growing_1d(events_.get(), "p", H5T_STD_U8LE, chunk);
    ms_ = h5::create_growing_1d(events_.get(), "ms_to_idx", H5T_STD_U64LE, 1 << 12);
  }

  void write(std::span<const Event> events) override {
    for (const Event& e : events) {
      if (count_ == 0) {
        t0_ = e.t >= 0 ? e.t / 1000 * 1000 : -((-e.t + 999) / 1000) * 1000;
        next_boundary_ = t0_;
      }
      if (e.t - t0_ > kMaxIndexedSpanUs)
        throw std::runtime_error("event at t=" + std::to_string(e.t) + " us lies more than " +
                                 std::to_string(kMaxIndexedSpanUs / 3'600'000'000LL) +
                                 " h after the first one; refusing to build a millisecond index that long");
      while (next_boundary_ <= e.t) {
        ms_buf_.push_back(count_);
        next_boundary_ += 1000;
        if (ms_buf_.size() == (1u << 16)) flush();
      }
      tb_.push_back(e.t);
      xb_.push_back(e.x);
      yb_.push_back(e.y);
      pb_.push_back(e.p);
      ++count_;
      if (tb_.size() == (1u << 16)) flush();
    }
  }

  hid_t file() const { return file_.get(); }

  void close() override {
    ms_buf_.push_back(count_);
    flush();
    h5::write_attr_i64(ms_.get(), "t0_us", t0_);
    ms_.reset();
    t_.reset(), x_.reset(), y_.reset(), p_.reset(), events_.reset();
    h5::check(H5Fflush(file_.get(), H5F_SCOPE_GLOBAL), "cannot flush " + tmp_.path());
    file_.reset();
    tmp_.commit();
  }

 private:
  void flush() {
    h5::append_1d(t_.get(), H5T_NATIVE_INT64, tb_.data(), tb_.size());
    h5::append_1d(x_.get(), H5T_NATIVE_UINT16, xb_.data(), xb_.size());
    h5::append_1d(y_.get(), H5T_NATIVE_UINT16, yb_.data(), yb_.size());
    h5::append_1d(p_.get(), H5T_NATIVE_UINT8, pb_.data(), pb_.size());
    h5::append_1d(ms_.get(), H5T_NATIVE_UINT64, ms_buf_.data(), ms_buf_.size());
    tb_.clear(), xb_.clear(), yb_.clear(), pb_.clear(), ms_buf_.clear();
  }

  TempFile tmp_;  // declared first: destroyed last, after the HDF5 handles close
  h5::H5Id file_, events_, t_, x_, y_, p_, ms_;
  std::vector<std::int64_t> tb_;
  std::vector<std::uint16_t> xb_, yb_;
  std::vector<std::uint8_t> pb_;
  std::vector<std::uint64_t> ms_buf_;
  std::uint64_t count_ = 0;
  std::int64_t t0_ = 0, next_boundary_ = 0;
};

}  // namespace

std::unique_ptr<EventReader> open_hdf5_events(const std::string& path) { return std::make_unique<Hdf5Reader>(path); }

std::unique_ptr<EventWriter> open_yelan_h5_writer(const std::string& path, const StreamInfo& info) {
  return std::make_unique<YelanH5Writer>(path, info);
}

std::int64_t yelan_h5_file(EventWriter& writer) {
  auto* w = dynamic_cast<YelanH5Writer*>(&writer);
  if (!w) throw std::invalid_argument("not a yelan HDF5 recording writer");
  return w->file();
}

}  // namespace yelan::camera
