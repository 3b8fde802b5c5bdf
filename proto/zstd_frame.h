#pragma once
// One zstd frame in, one out: the two places that compress (a flush's splats on the wire,
// proto/splat_codec.h; the durable store's checkpoints, coordinator/job_store.h) share these so
// that a frame's size is checked the same way at both.
#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace farm {

// One frame of `size` bytes at `level` (1: the fastest; both users write far more often than
// they read). Throws std::runtime_error only when zstd itself fails.
std::string zstdCompress(const void* data, size_t size, int level = 1);

// Decompresses `frame` into exactly `size` bytes at `out`; false when the frame announces or
// holds any other size, or is corrupt.
bool zstdDecompressExact(const std::string& frame, void* out, size_t size);

// One frame of `chunks` x `chunkSize` bytes, decompressed a chunk at a time into a buffer of
// one chunk: each(chunk, k) for k = 0 .. chunks - 1, in order. False as zstdDecompressExact
// (then `each` may have seen some chunks).
bool zstdDecompressChunks(const std::string& frame, size_t chunkSize, size_t chunks,
                          const std::function<void(const char* chunk, size_t k)>& each);

// Frames written one after another (zstdCompress's, concatenated), each decompressed into
// exactly its (out, size); false when there are more or fewer frames or any is as above.
bool zstdDecompressFrames(const std::string& frames,
                          const std::vector<std::pair<void*, size_t>>& outs);

}  // namespace farm
