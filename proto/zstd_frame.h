#pragma once
// One zstd frame in, one out: the two places that compress (a flush's splats on the wire,
// proto/splat_codec.h; the durable store's checkpoints, coordinator/job_store.h) share these so
// that a frame's size is checked the same way at both.
#include <cstddef>
#include <string>

namespace farm {

// One frame of `size` bytes at `level` (1: the fastest; both users write far more often than
// they read). Throws std::runtime_error only when zstd itself fails.
std::string zstdCompress(const void* data, size_t size, int level = 1);

// Decompresses `frame` into exactly `size` bytes at `out`; false when the frame announces or
// holds any other size, or is corrupt.
bool zstdDecompressExact(const std::string& frame, void* out, size_t size);

}  // namespace farm
