#include "proto/zstd_frame.h"

#include <zstd.h>

#include <memory>
#include <stdexcept>

namespace farm {

std::string zstdCompress(const void* data, size_t size, int level) {
  // Into a buffer of the bound left unwritten (its pages untouched but for the frame), then a
  // string of the frame's size: a string of the bound would keep the whole bound resident (a
  // dense 3840x2160 film's is 95 MiB, its frame a sixth of that).
  const size_t bound = ZSTD_compressBound(size);
  std::unique_ptr<char[]> buffer(new char[bound]);
  const size_t n = ZSTD_compress(buffer.get(), bound, data, size, level);
  if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  return std::string(buffer.get(), n);
}

namespace {

bool decompressExact(const char* frame, size_t frameSize, void* out, size_t size) {
  // The announced size first: a frame cannot make us write past `size`, and a frame without
  // the content size (ZSTD_CONTENTSIZE_UNKNOWN) is not one we wrote.
  const unsigned long long content = ZSTD_getFrameContentSize(frame, frameSize);
  if (content != size) return false;
  const size_t n = ZSTD_decompress(out, size, frame, frameSize);
  return !ZSTD_isError(n) && n == size;
}

}  // namespace

bool zstdDecompressExact(const std::string& frame, void* out, size_t size) {
  return decompressExact(frame.data(), frame.size(), out, size);
}

bool zstdDecompressChunks(const std::string& frame, size_t chunkSize, size_t chunks,
                          const std::function<void(const char* chunk, size_t k)>& each) {
  const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (chunkSize == 0 || content != chunkSize * chunks) return false;
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> context(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!context) return false;
  std::unique_ptr<char[]> chunk(new char[chunkSize]);
  ZSTD_inBuffer in{frame.data(), frame.size(), 0};
  size_t k = 0, left = 1;
  while (k < chunks) {
    ZSTD_outBuffer out{chunk.get(), chunkSize, 0};
    while (out.pos < out.size) {
      const size_t before = in.pos + out.pos;
      left = ZSTD_decompressStream(context.get(), &out, &in);
      if (ZSTD_isError(left) || (left == 0 && out.pos < out.size) ||
          in.pos + out.pos == before)  // no progress: the frame ends short
        return false;
    }
    each(chunk.get(), k++);
  }
  while (left != 0) {  // what may follow the last byte: the frame's end, its checksum
    char spare;  // no room for output (a null buffer trips UBSan in older zstd releases)
    ZSTD_outBuffer none{&spare, 0, 0};
    const size_t before = in.pos;
    left = ZSTD_decompressStream(context.get(), &none, &in);
    if (ZSTD_isError(left) || (left != 0 && in.pos == before)) return false;
  }
  return in.pos == in.size;
}

bool zstdDecompressFrames(const std::string& frames,
                          const std::vector<std::pair<void*, size_t>>& outs) {
  size_t at = 0;
  for (const auto& [out, size] : outs) {
    if (at >= frames.size()) return false;
    const size_t length = ZSTD_findFrameCompressedSize(frames.data() + at, frames.size() - at);
    if (ZSTD_isError(length) || !decompressExact(frames.data() + at, length, out, size))
      return false;
    at += length;
  }
  return at == frames.size();
}

}  // namespace farm
