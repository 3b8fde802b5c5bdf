// zstd frames as the wire and the durable store use them: frames one after another come back
// each into its own size, and a frame read a chunk at a time gives its chunks in order.
#include "proto/zstd_frame.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <cstring>
#include <numeric>

namespace farm {
namespace {

std::vector<double> counting(size_t n, double from) {
  std::vector<double> v(n);
  std::iota(v.begin(), v.end(), from);
  return v;
}

TEST(ZstdFrame, FramesOneAfterAnotherComeBackEachIntoItsOwn) {
  const std::vector<double> a = counting(1000, 0.5);
  const std::vector<float> b(300, 2.25f);
  const std::string frames = zstdCompress(a.data(), a.size() * sizeof(double)) +
                             zstdCompress(b.data(), b.size() * sizeof(float));
  std::vector<double> a2(a.size());
  std::vector<float> b2(b.size());
  ASSERT_TRUE(zstdDecompressFrames(
      frames, {{a2.data(), a2.size() * sizeof(double)}, {b2.data(), b2.size() * sizeof(float)}}));
  EXPECT_EQ(a2, a);
  EXPECT_EQ(b2, b);
  // One frame too few, one too many, or a frame of another size: refused.
  EXPECT_FALSE(zstdDecompressFrames(frames, {{a2.data(), a2.size() * sizeof(double)}}));
  EXPECT_FALSE(zstdDecompressFrames(frames, {{a2.data(), a2.size() * sizeof(double)},
                                             {b2.data(), b2.size() * sizeof(float)},
                                             {b2.data(), b2.size() * sizeof(float)}}));
  EXPECT_FALSE(zstdDecompressFrames(
      frames, {{a2.data(), a2.size() * sizeof(double)}, {b2.data(), 4 * sizeof(float)}}));
}

TEST(ZstdFrame, AFrameReadAChunkAtATimeGivesItsChunksInOrder) {
  const std::vector<double> films = counting(3 * 5000, 1.0);  // three films of 5000 values
  for (bool checksum : {false, true}) {
    std::string frame;
    if (checksum) {  // a frame that ends in a checksum after its last byte
      ZSTD_CCtx* c = ZSTD_createCCtx();
      ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);
      frame.resize(ZSTD_compressBound(films.size() * sizeof(double)));
      frame.resize(ZSTD_compress2(c, frame.data(), frame.size(), films.data(),
                                  films.size() * sizeof(double)));
      ZSTD_freeCCtx(c);
    } else {
      frame = zstdCompress(films.data(), films.size() * sizeof(double));
    }
    std::vector<size_t> order;
    std::vector<double> back;
    auto keep = [&](const char* chunk, size_t k) {
      order.push_back(k);
      const size_t at = back.size();
      back.resize(at + 5000);
      std::memcpy(&back[at], chunk, 5000 * sizeof(double));
    };
    ASSERT_TRUE(zstdDecompressChunks(frame, 5000 * sizeof(double), 3, keep)) << checksum;
    EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2}));
    EXPECT_EQ(back, films);
    // Chunks that do not make up the frame's size, and a frame cut short, are refused.
    auto ignore = [](const char*, size_t) {};
    EXPECT_FALSE(zstdDecompressChunks(frame, 5000 * sizeof(double), 2, ignore));
    EXPECT_FALSE(zstdDecompressChunks(frame, 4000 * sizeof(double), 3, ignore));
    EXPECT_FALSE(
        zstdDecompressChunks(frame.substr(0, frame.size() - 5), 5000 * sizeof(double), 3, ignore))
        << checksum;
  }
}

}  // namespace
}  // namespace farm
