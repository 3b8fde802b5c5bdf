#include "proto/zstd_frame.h"

#include <zstd.h>

#include <stdexcept>

namespace farm {

std::string zstdCompress(const void* data, size_t size, int level) {
  std::string out(ZSTD_compressBound(size), '\0');
  const size_t n = ZSTD_compress(out.data(), out.size(), data, size, level);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

bool zstdDecompressExact(const std::string& frame, void* out, size_t size) {
  // The announced size first: a frame cannot make us write past `size`, and a frame without
  // the content size (ZSTD_CONTENTSIZE_UNKNOWN) is not one we wrote.
  const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (content != size) return false;
  const size_t n = ZSTD_decompress(out, size, frame.data(), frame.size());
  return !ZSTD_isError(n) && n == size;
}

}  // namespace farm
