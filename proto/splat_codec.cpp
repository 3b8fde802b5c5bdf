#include "proto/splat_codec.h"

#include <zstd.h>

#include <cstring>

#include "proto/zstd_frame.h"

namespace farm {

namespace {

// zstd level 1: a worker compresses every flush it sends; the fast levels already remove the
// zero runs that make up most of a sparse film.
constexpr int kZstdLevel = 1;

// The wire is little-endian; on such a machine a dense film's bytes are already its wire form,
// and are compressed from, and decompressed into, the film itself, without a copy of it (a
// 3840x2160 film is 95 MiB).
constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

void putU32(std::string* out, uint32_t v) {
  char b[4];
  for (int i = 0; i < 4; ++i) b[i] = char((v >> (8 * i)) & 0xff);
  out->append(b, 4);
}
void putF32(std::string* out, float f) {
  uint32_t v;
  std::memcpy(&v, &f, 4);
  putU32(out, v);
}
uint32_t getU32(const char* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(uint8_t(p[i])) << (8 * i);
  return v;
}
float getF32(const char* p) {
  const uint32_t v = getU32(p);
  float f;
  std::memcpy(&f, &v, 4);
  return f;
}

}  // namespace

uint64_t maxEncodedSplatBytes(size_t values) {
  const uint64_t dense = uint64_t(values) * sizeof(float);
  return std::max<uint64_t>(dense, ZSTD_compressBound(size_t(dense)));
}

EncodedSplats encodeSplats(const std::vector<float>& dense) {
  EncodedSplats e;
  const size_t pixels = dense.size() / 3;
  size_t touched = 0;
  for (size_t p = 0; p < pixels; ++p) {
    touched += dense[3 * p] != 0.0f || dense[3 * p + 1] != 0.0f || dense[3 * p + 2] != 0.0f;
  }
  const size_t denseBytes = dense.size() * sizeof(float);
  e.sparse = touched * kSparseRecordBytes < denseBytes;
  // The form before compression: a dense film's own bytes where they are already its wire form
  // (a little-endian machine), else written out here.
  const bool written = e.sparse || !kLittleEndian;
  std::string raw;
  if (e.sparse) {
    raw.reserve(touched * kSparseRecordBytes);
    for (size_t p = 0; p < pixels; ++p) {
      if (dense[3 * p] == 0.0f && dense[3 * p + 1] == 0.0f && dense[3 * p + 2] == 0.0f) continue;
      putU32(&raw, uint32_t(p));
      for (int c = 0; c < 3; ++c) putF32(&raw, dense[3 * p + size_t(c)]);
    }
  } else if (written) {
    raw.resize(denseBytes);
    for (size_t i = 0; i < dense.size(); ++i) {
      std::string word;
      putF32(&word, dense[i]);
      std::memcpy(&raw[4 * i], word.data(), 4);
    }
  }
  const char* rawData = written ? raw.data() : reinterpret_cast<const char*>(dense.data());
  e.rawBytes = written ? raw.size() : denseBytes;
  std::string frame = zstdCompress(rawData, size_t(e.rawBytes), kZstdLevel);
  e.compressed = frame.size() < e.rawBytes;
  if (e.compressed) {
    e.bytes = std::move(frame);
  } else if (written) {
    e.bytes = std::move(raw);
  } else {
    e.bytes.assign(rawData, size_t(e.rawBytes));
  }
  return e;
}

bool decodeSplats(const EncodedSplats& e, size_t values, std::vector<float>* dense,
                  std::string* error) {
  const uint64_t denseBytes = uint64_t(values) * sizeof(float);
  const size_t pixels = values / 3;
  if (e.bytes.size() > maxEncodedSplatBytes(values)) {
    *error = "the splats take " + std::to_string(e.bytes.size()) + " bytes, more than a " +
             std::to_string(values) + "-value film ever needs";
    return false;
  }
  const uint64_t expectedRaw = e.sparse ? e.rawBytes : denseBytes;
  if (e.sparse &&
      (e.rawBytes % kSparseRecordBytes != 0 || e.rawBytes / kSparseRecordBytes > pixels)) {
    *error = "sparse splats of " + std::to_string(e.rawBytes) + " bytes: not whole " +
             std::to_string(kSparseRecordBytes) + "-byte records for at most " +
             std::to_string(pixels) + " pixels";
    return false;
  }
  // A dense film's form before compression is, on a little-endian machine, the film's own
  // bytes: it is decompressed (or copied) straight into the film.
  const bool direct = kLittleEndian && !e.sparse;
  if (direct) dense->assign(values, 0.0f);
  std::string decompressed;
  const char* raw = e.bytes.data();
  if (e.compressed) {
    char* target = reinterpret_cast<char*>(dense->data());
    if (!direct) {
      decompressed.resize(size_t(expectedRaw));
      target = decompressed.data();
    }
    if (!zstdDecompressExact(e.bytes, target, size_t(expectedRaw))) {
      *error = "the compressed splats are corrupt or do not hold the " +
               std::to_string(expectedRaw) + " bytes the header announces";
      return false;
    }
    raw = target;
  } else if (e.bytes.size() != expectedRaw) {
    *error = "the splats take " + std::to_string(e.bytes.size()) + " bytes, not " +
             std::to_string(expectedRaw);
    return false;
  } else if (direct) {
    std::memcpy(dense->data(), raw, size_t(expectedRaw));
  }
  if (direct) return true;
  dense->assign(values, 0.0f);
  if (!e.sparse) {
    for (size_t i = 0; i < values; ++i) (*dense)[i] = getF32(raw + 4 * i);
    return true;
  }
  int64_t previous = -1;
  for (size_t at = 0; at < size_t(expectedRaw); at += kSparseRecordBytes) {
    const uint32_t pixel = getU32(raw + at);
    if (int64_t(pixel) <= previous || pixel >= pixels) {
      *error = "a sparse splat record names pixel " + std::to_string(pixel) +
               (pixel >= pixels ? " (off the film)" : " (out of order)");
      return false;
    }
    previous = pixel;
    for (int c = 0; c < 3; ++c) {
      (*dense)[3 * size_t(pixel) + size_t(c)] = getF32(raw + at + 4 + 4 * size_t(c));
    }
  }
  return true;
}

}  // namespace farm
