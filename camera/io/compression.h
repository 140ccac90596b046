// LZ4-frame and Zstd (de)compression of whole packets, with a cap on the decompressed size
// so a corrupt or hostile packet cannot make us allocate without bound.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace yelan::camera {

enum class Codec { none, lz4, zstd };

// Decompresses one frame. On failure returns false and puts the reason in `problem`.
bool decompress(Codec codec, const unsigned char* src, std::size_t n, std::size_t max_out,
                std::vector<unsigned char>& out, std::string& problem);

std::vector<unsigned char> compress_lz4_frame(const unsigned char* src, std::size_t n);

}  // namespace yelan::camera
