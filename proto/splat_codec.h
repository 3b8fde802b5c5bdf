#pragma once
// How a flush's film travels (proto/farm.proto, FlushHeader): as small as its information. A
// Markov chain's flush touches few pixels, so it goes as (pixel, RGB) records when those are
// fewer bytes than the dense film; either form is then zstd-compressed when that is smaller.
// Network-free, so that both ends and their tests share one codec.
#include <cstdint>
#include <string>
#include <vector>

namespace farm {

struct EncodedSplats {
  bool sparse = false;      // (uint32 pixel, 3 x float32) records, pixels ascending; else dense
  bool compressed = false;  // `bytes` is one zstd frame of the form above
  uint64_t rawBytes = 0;    // size of the form above before compression
  std::string bytes;        // what goes on the wire (little-endian throughout)
};

// Bytes of one sparse record: a pixel index and its three channels.
inline constexpr size_t kSparseRecordBytes = 16;

// The smallest of the forms for a dense film of width*height*3 values.
EncodedSplats encodeSplats(const std::vector<float>& dense);

// The largest `bytes` may be for a film of `values` floats: what an honest encoder can send
// (a dense film, or a compressed frame of one), so that a header cannot make a receiver
// allocate more.
uint64_t maxEncodedSplatBytes(size_t values);

// Back to the dense film of `values` floats (a multiple of 3); false with *error saying what is
// wrong (a frame of another size, records out of order or off the film).
bool decodeSplats(const EncodedSplats& encoded, size_t values, std::vector<float>* dense,
                  std::string* error);

}  // namespace farm
