// Chunks read as stored and inflated outside HDF5's lock. A thread-safe HDF5 holds one
// global lock through H5Dread, inflating included, so threads reading different files take
// turns at zlib; H5Dread_chunk hands over the stored bytes and the inflating (zlib needs no
// lock) runs on the caller's thread, beside the others.
#pragma once
#include <hdf5.h>

#include <cstddef>
#include <vector>

namespace yelan::camera::h5 {

class RawChunkReader {
 public:
  // Whether `dataset` can be read this way: chunked, its filters deflate and shuffle (each at
  // most once, shuffle first) or none, its elements little-endian integers of 1, 2, 4 or 8
  // bytes with every bit a value bit, or IEEE floats, on a little-endian machine. Otherwise read it with H5Dread.
  static bool suits(hid_t dataset);
  explicit RawChunkReader(hid_t dataset);  // throws H5Failure unless suits(dataset)

  const std::vector<hsize_t>& chunk() const { return chunk_; }
  std::size_t element_bytes() const { return element_; }
  std::size_t chunk_bytes() const { return bytes_; }

  // The chunk starting at `coord` (a multiple of chunk() in every dimension) into `out`,
  // chunk_bytes() long, its elements as the file stores them. False when the chunk was never
  // written (H5Dread gives the fill value there). Throws H5Failure on a chunk that does not
  // inflate to exactly chunk_bytes().
  bool read(hid_t dataset, const hsize_t* coord, std::vector<unsigned char>& out);

 private:
  std::vector<hsize_t> chunk_;
  std::size_t element_ = 0, bytes_ = 0;
  int shuffle_ = -1, deflate_ = -1;  // their places in the pipeline
  std::vector<unsigned char> stored_, inflated_;
};

}  // namespace yelan::camera::h5
