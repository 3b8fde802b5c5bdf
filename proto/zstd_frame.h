#pragma once
// One zstd frame in, one out: the two places that compress (a flush's splats on the wire,
// proto/splat_codec.h; the durable store's checkpoints, coordinator/job_store.h) share these so
// that a frame's size is checked the same way at both.
#include <cstddef>
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

// Frames written one after another (zstdCompress's, concatenated), each decompressed into
// exactly its (out, size); false when there are more or fewer frames or any is as above.
bool zstdDecompressFrames(const std::string& frames,
                          const std::vector<std::pair<void*, size_t>>& outs);

}  // namespace farm
