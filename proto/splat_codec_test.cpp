// The flush codec (proto/splat_codec.h): every form decodes to the film it came from, a Markov
// chain's flush goes sparse and small, and a malformed encoding is refused with a reason, never
// decoded into a wrong film.
#include "proto/splat_codec.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "proto/zstd_frame.h"

namespace farm {
namespace {

std::vector<float> film(size_t pixels, double touched, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> f(pixels * 3, 0.0f);
  for (size_t p = 0; p < pixels; ++p) {
    if (u(rng) >= touched) continue;
    for (int c = 0; c < 3; ++c) f[3 * p + size_t(c)] = u(rng) * 10;
  }
  return f;
}

TEST(SplatCodec, EveryFormDecodesToItsFilm) {
  const size_t pixels = 64 * 48;
  for (double touched : {0.0, 0.001, 0.02, 0.5, 0.8, 1.0}) {
    const std::vector<float> original = film(pixels, touched, 7);
    const EncodedSplats e = encodeSplats(original);
    std::vector<float> back;
    std::string error;
    ASSERT_TRUE(decodeSplats(e, original.size(), &back, &error)) << touched << ": " << error;
    EXPECT_EQ(back, original) << "touched " << touched;
    // Sparse exactly when the records are smaller than the dense film.
    EXPECT_EQ(e.sparse, touched < 0.7) << touched;
    EXPECT_LE(e.bytes.size(), original.size() * sizeof(float));
  }
}

// The dense form on the wire is each value's float32 bits, least significant byte first,
// whatever the machine: what a worker sends from its film's own bytes decodes, byte by byte, to
// that, compressed (a film with zero runs) or not (random bits, which zstd cannot shrink).
TEST(SplatCodec, TheDenseFormIsLittleEndianFloats) {
  for (double touched : {0.8, 1.0}) {
    std::vector<float> original = film(64 * 48, touched, 3);
    if (touched == 1.0) {
      std::mt19937 rng(5);
      for (float& v : original) {
        const uint32_t bits = uint32_t(rng());  // every bit random: nothing for zstd to take
        std::memcpy(&v, &bits, 4);
      }
    }
    const EncodedSplats e = encodeSplats(original);
    ASSERT_FALSE(e.sparse);
    EXPECT_EQ(e.compressed, touched < 1.0);
    std::string raw = e.bytes;
    if (e.compressed) {
      raw.assign(original.size() * 4, '\0');
      ASSERT_TRUE(zstdDecompressExact(e.bytes, raw.data(), raw.size()));
    }
    ASSERT_EQ(raw.size(), original.size() * 4);
    for (size_t i = 0; i < original.size(); ++i) {
      uint32_t bits;
      std::memcpy(&bits, &original[i], 4);
      for (int b = 0; b < 4; ++b)
        ASSERT_EQ(uint8_t(raw[4 * i + size_t(b)]), uint8_t(bits >> (8 * b))) << i;
    }
  }
}

TEST(SplatCodec, AMarkovChainsFlushIsSmall) {
  const std::vector<float> original = film(256 * 256, 0.02, 3);
  const EncodedSplats e = encodeSplats(original);
  EXPECT_TRUE(e.sparse);
  // 2% of the pixels at 16 bytes each: about 8% of the dense film, less once compressed.
  EXPECT_LT(double(e.bytes.size()), 0.09 * double(original.size() * sizeof(float)));
}

TEST(SplatCodec, MalformedEncodingsAreRefused) {
  const size_t values = 8 * 8 * 3;
  std::vector<float> back;
  std::string error;
  auto refuse = [&](const EncodedSplats& e, const std::string& why) {
    error.clear();
    EXPECT_FALSE(decodeSplats(e, values, &back, &error)) << why;
    EXPECT_FALSE(error.empty()) << why;
  };
  auto record = [](uint32_t pixel) {
    std::string r(kSparseRecordBytes, '\0');
    std::memcpy(&r[0], &pixel, 4);
    const float one = 1.0f;
    for (int c = 0; c < 3; ++c) std::memcpy(&r[4 + 4 * c], &one, 4);
    return r;
  };
  EncodedSplats sparse;
  sparse.sparse = true;
  sparse.bytes = record(5) + record(3);
  sparse.rawBytes = sparse.bytes.size();
  refuse(sparse, "records out of order");
  sparse.bytes = record(3) + record(3);
  refuse(sparse, "the same pixel twice");
  sparse.bytes = record(64);
  sparse.rawBytes = sparse.bytes.size();
  refuse(sparse, "a pixel off the film");
  sparse.bytes = record(1).substr(0, 15);
  sparse.rawBytes = 15;
  refuse(sparse, "a partial record");
  EncodedSplats dense;
  dense.bytes = std::string(values * 4 - 4, '\0');
  refuse(dense, "a short dense film");
  dense.bytes = std::string(maxEncodedSplatBytes(values) + 1, '\0');
  refuse(dense, "more bytes than any film needs");
  // A compressed frame whose content is not what the header says.
  EncodedSplats frame = encodeSplats(std::vector<float>(values, 0.0f));
  ASSERT_TRUE(frame.sparse);
  frame.compressed = true;
  frame.bytes = "not a zstd frame";
  refuse(frame, "garbage for a frame");
  EncodedSplats big = encodeSplats(std::vector<float>(values * 4, 1.0f));  // a larger film's
  ASSERT_FALSE(big.sparse);
  refuse(big, "another film's dense film");
  big.sparse = true;
  refuse(big, "a dense film taken for records");
  EncodedSplats ok = encodeSplats(film(64, 0.05, 1));
  ASSERT_TRUE(decodeSplats(ok, values, &back, &error)) << error;
  ok.rawBytes += kSparseRecordBytes;
  refuse(ok, "a raw size the frame does not hold");
}

}  // namespace
}  // namespace farm
