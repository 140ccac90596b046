#include "camera/io/compression.h"

#include <lz4frame.h>
#include <zstd.h>

#include <memory>
#include <stdexcept>

namespace yelan::camera {
namespace {

struct Lz4Ctx {
  LZ4F_dctx* ctx = nullptr;
  Lz4Ctx() { LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION); }
  ~Lz4Ctx() { LZ4F_freeDecompressionContext(ctx); }
};

struct ZstdCtx {
  ZSTD_DStream* ctx = ZSTD_createDStream();
  ~ZstdCtx() { ZSTD_freeDStream(ctx); }
};

bool lz4_frame(const unsigned char* src, std::size_t n, std::size_t max_out,
               std::vector<unsigned char>& out, std::string& problem) {
  Lz4Ctx c;
  if (!c.ctx) {
    problem = "cannot create an LZ4 context";
    return false;
  }
  out.clear();
  std::size_t in_pos = 0;
  std::size_t hint = 1;
  while (true) {
    if (out.size() == max_out) {
      problem = "LZ4 packet decompresses to more than " + std::to_string(max_out) + " bytes";
      return false;
    }
    std::size_t old = out.size();
    std::size_t room = std::min<std::size_t>(max_out - old, std::max<std::size_t>(64 << 10, n * 4));
    out.resize(old + room);
    std::size_t dst_n = room, src_n = n - in_pos;
    hint = LZ4F_decompress(c.ctx, out.data() + old, &dst_n, src + in_pos, &src_n, nullptr);
    out.resize(old + dst_n);
    in_pos += src_n;
    if (LZ4F_isError(hint)) {
      problem = std::string("corrupt LZ4 packet: ") + LZ4F_getErrorName(hint);
      return false;
    }
    if (hint == 0) break;                    // frame complete
    if (src_n == 0 && dst_n == 0) break;     // no progress: the input ran out
  }
  if (hint != 0) {
    problem = "LZ4 packet ends before its frame does";
    return false;
  }
  return true;
}

bool zstd_frame(const unsigned char* src, std::size_t n, std::size_t max_out,
                std::vector<unsigned char>& out, std::string& problem) {
  ZstdCtx c;
  if (!c.ctx) {
    problem = "cannot create a Zstd context";
    return false;
  }
  ZSTD_initDStream(c.ctx);
  out.clear();
  ZSTD_inBuffer in{src, n, 0};
  std::size_t ret = 1;
  while (true) {
    if (out.size() == max_out) {
      problem = "Zstd packet decompresses to more than " + std::to_string(max_out) + " bytes";
      return false;
    }
    std::size_t old = out.size();
    std::size_t room = std::min<std::size_t>(max_out - old, std::max<std::size_t>(64 << 10, n * 4));
    out.resize(old + room);
    ZSTD_outBuffer ob{out.data() + old, room, 0};
    ret = ZSTD_decompressStream(c.ctx, &ob, &in);
    out.resize(old + ob.pos);
    if (ZSTD_isError(ret)) {
      problem = std::string("corrupt Zstd packet: ") + ZSTD_getErrorName(ret);
      return false;
    }
    if (ret == 0) break;
    if (in.pos == in.size && ob.pos < room) break;  // needs more input than there is
  }
  if (ret != 0) {
    problem = "Zstd packet ends before its frame does";
    return false;
  }
  return true;
}

}  // namespace

bool decompress(Codec codec, const unsigned char* src, std::size_t n, std::size_t max_out,
                std::vector<unsigned char>& out, std::string& problem) {
  switch (codec) {
    case Codec::none:
      if (n > max_out) {
        problem = "packet larger than " + std::to_string(max_out) + " bytes";
        return false;
      }
      out.assign(src, src + n);
      return true;
    case Codec::lz4:
      return lz4_frame(src, n, max_out, out, problem);
    case Codec::zstd:
      return zstd_frame(src, n, max_out, out, problem);
  }
  return false;
}

std::vector<unsigned char> compress_lz4_frame(const unsigned char* src, std::size_t n) {
  LZ4F_preferences_t prefs{};
  prefs.frameInfo.contentSize = n;
  std::vector<unsigned char> out(LZ4F_compressFrameBound(n, &prefs));
  std::size_t got = LZ4F_compressFrame(out.data(), out.size(), src, n, &prefs);
  if (LZ4F_isError(got)) throw std::runtime_error(std::string("LZ4 compression failed: ") + LZ4F_getErrorName(got));
  out.resize(got);
  return out;
}

}  // namespace yelan::camera
