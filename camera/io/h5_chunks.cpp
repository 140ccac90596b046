#include "camera/io/h5_chunks.h"

#include <zlib.h>

#include <bit>
#include <cstring>
#include <string>

#include "camera/io/h5.h"

namespace yelan::camera::h5 {
namespace {

struct Pipeline {
  bool ok = false;
  int shuffle = -1, deflate = -1;
};

Pipeline pipeline(hid_t dcpl) {
  Pipeline p;
  const int n = H5Pget_nfilters(dcpl);
  if (n < 0 || n > 2) return p;
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, config = 0;
    std::size_t nvalues = 0;
    const H5Z_filter_t id = H5Pget_filter2(dcpl, unsigned(i), &flags, &nvalues, nullptr, 0, nullptr, &config);
    if (id == H5Z_FILTER_SHUFFLE && p.shuffle < 0 && p.deflate < 0) p.shuffle = i;
    else if (id == H5Z_FILTER_DEFLATE && p.deflate < 0) p.deflate = i;
    else return p;
  }
  p.ok = true;
  return p;
}

// HDF5's shuffle stores byte j of every element before byte j+1 of any.
void unshuffle(const unsigned char* in, std::size_t bytes, std::size_t element, unsigned char* out) {
  const std::size_t n = bytes / element;
  for (std::size_t j = 0; j < element; ++j)
    for (std::size_t i = 0; i < n; ++i) out[i * element + j] = in[j * n + i];
  std::memcpy(out + n * element, in + n * element, bytes - n * element);
}

}  // namespace

bool RawChunkReader::suits(hid_t dataset) {
  if (std::endian::native != std::endian::little) return false;
  H5Id dcpl(H5Dget_create_plist(dataset));
  if (!dcpl.valid() || H5Pget_layout(dcpl.get()) != H5D_CHUNKED || !pipeline(dcpl.get()).ok) return false;
  H5Id type(H5Dget_type(dataset));
  if (!type.valid()) return false;
  const H5T_class_t cls = H5Tget_class(type.get());
  const std::size_t size = H5Tget_size(type.get());
  if (cls == H5T_FLOAT) {
    if (H5Tequal(type.get(), H5T_IEEE_F32LE) <= 0 && H5Tequal(type.get(), H5T_IEEE_F64LE) <= 0) return false;
  } else if (cls == H5T_INTEGER) {
    // Every bit a value bit: a file may declare 12-bit integers padded to 2 bytes.
    if (size != 1 && size != 2 && size != 4 && size != 8) return false;
    if (H5Tget_precision(type.get()) != size * 8 || H5Tget_offset(type.get()) != 0) return false;
    if (size > 1 && H5Tget_order(type.get()) != H5T_ORDER_LE) return false;
  } else {
    return false;
  }
  return h5::chunk_bytes(dataset) > 0;
}

RawChunkReader::RawChunkReader(hid_t dataset) {
  if (!suits(dataset)) throw H5Failure("dataset not stored as chunks of deflate and shuffle alone");
  H5Id dcpl = check(H5Dget_create_plist(dataset), "dataset properties");
  hsize_t dims[32] = {};
  const int rank = H5Pget_chunk(dcpl.get(), 32, dims);
  if (rank < 1) throw H5Failure("bad chunk shape");
  chunk_.assign(dims, dims + rank);
  H5Id type = check(H5Dget_type(dataset), "dataset type");
  element_ = H5Tget_size(type.get());
  bytes_ = h5::chunk_bytes(dataset);
  const Pipeline p = pipeline(dcpl.get());
  shuffle_ = p.shuffle;
  deflate_ = p.deflate;
}

bool RawChunkReader::read(hid_t dataset, const hsize_t* coord, std::vector<unsigned char>& out) {
  unsigned mask = 0;
  haddr_t addr = HADDR_UNDEF;
  hsize_t stored = 0;
  if (H5Dget_chunk_info_by_coord(dataset, coord, &mask, &addr, &stored) < 0) throw H5Failure("bad chunk index");
  if (addr == HADDR_UNDEF) return false;
  // Deflate never stores more than compressBound (HDF5 keeps the chunk raw where it would).
  if (stored == 0 || stored > compressBound(uLong(bytes_)) + 64)
    throw H5Failure("chunk stores " + std::to_string(stored) + " bytes where it holds " + std::to_string(bytes_));
  stored_.resize(stored);
  std::uint32_t filters = 0;
  check(H5Dread_chunk(dataset, H5P_DEFAULT, coord, &filters, stored_.data()), "read chunk");
  const bool inflate = deflate_ >= 0 && !(filters >> deflate_ & 1u);
  const bool shuffled = shuffle_ >= 0 && !(filters >> shuffle_ & 1u) && element_ > 1;
  out.resize(bytes_);
  unsigned char* inflated = shuffled ? (inflated_.resize(bytes_), inflated_.data()) : out.data();
  if (inflate) {
    uLongf got = uLongf(bytes_);
    const int rc = uncompress(inflated, &got, stored_.data(), uLong(stored));
    if (rc != Z_OK || got != bytes_)
      throw H5Failure("chunk does not inflate to its " + std::to_string(bytes_) + " bytes (zlib " + std::to_string(rc) + ")");
  } else {
    if (stored != bytes_)
      throw H5Failure("chunk stores " + std::to_string(stored) + " bytes unfiltered where it holds " + std::to_string(bytes_));
    std::memcpy(inflated, stored_.data(), bytes_);
  }
  if (shuffled) unshuffle(inflated, bytes_, element_, out.data());
  return true;
}

}  // namespace yelan::camera::h5
