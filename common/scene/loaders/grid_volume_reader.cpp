#include "common/scene/loaders/grid_volume_reader.h"

#include <cmath>
#include <cstdint>
#include <cstring>

namespace farm {

namespace {

constexpr size_t kHeaderBytes = 4 + 4 * 5 + 4 * 6;
constexpr uint64_t kMaxValues = uint64_t(1) << 28;

int32_t readInt(const std::string& b, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | uint8_t(b[at + size_t(i)]);
  return int32_t(v);
}

float readFloat(const std::string& b, size_t at) {
  const uint32_t bits = uint32_t(readInt(b, at));
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

void writeInt(std::string* b, int32_t value) {
  const uint32_t v = uint32_t(value);
  for (int i = 0; i < 4; ++i) b->push_back(char((v >> (8 * i)) & 0xFF));
}

void writeFloat(std::string* b, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  writeInt(b, int32_t(bits));
}

}  // namespace

bool decodeGridVolume(const std::string& bytes, GridVolume* out, std::string* problem) {
  if (bytes.size() < kHeaderBytes) {
    *problem = "a grid volume file is at least " + std::to_string(kHeaderBytes) + " bytes long";
    return false;
  }
  if (bytes.compare(0, 3, "VOL") != 0) {
    *problem = "not a Mitsuba grid volume (it does not start with \"VOL\")";
    return false;
  }
  if (uint8_t(bytes[3]) != 3) {
    *problem = "grid volume version " + std::to_string(uint8_t(bytes[3])) + " (only 3 is read)";
    return false;
  }
  const int32_t encoding = readInt(bytes, 4);
  if (encoding != 1) {
    *problem = "grid volume encoding " + std::to_string(encoding) + " (only 1, float32, is read)";
    return false;
  }
  const int32_t nx = readInt(bytes, 8), ny = readInt(bytes, 12), nz = readInt(bytes, 16);
  const int32_t channels = readInt(bytes, 20);
  if (nx < 1 || ny < 1 || nz < 1 || channels < 1) {
    *problem = "a grid volume's resolution and channel count must be positive";
    return false;
  }
  const uint64_t count = uint64_t(nx) * uint64_t(ny) * uint64_t(nz);
  if (count * uint64_t(channels) > kMaxValues) {
    *problem = "the grid volume holds more than 2^28 values";
    return false;
  }
  const uint64_t expected = kHeaderBytes + 4 * count * uint64_t(channels);
  if (bytes.size() != expected) {
    *problem = "the grid volume has " + std::to_string(bytes.size()) + " bytes; its header says " +
               std::to_string(expected);
    return false;
  }
  for (int a = 0; a < 3; ++a) {
    out->boundsMin[a] = readFloat(bytes, 24 + 4 * size_t(a));
    out->boundsMax[a] = readFloat(bytes, 36 + 4 * size_t(a));
    if (!std::isfinite(out->boundsMin[a]) || !std::isfinite(out->boundsMax[a]) ||
        !(out->boundsMax[a] > out->boundsMin[a])) {
      *problem = "the grid volume's bounding box is empty or not finite";
      return false;
    }
  }
  out->nx = nx, out->ny = ny, out->nz = nz;
  out->values.resize(size_t(count));
  for (uint64_t i = 0; i < count; ++i) {
    const float v = readFloat(bytes, kHeaderBytes + 4 * size_t(i * uint64_t(channels)));
    if (!std::isfinite(v)) {
      *problem = "the grid volume holds a value that is not finite";
      return false;
    }
    out->values[size_t(i)] = v;
  }
  return true;
}

std::string encodeGridVolume(const GridVolume& volume) {
  std::string b = "VOL";
  b.push_back(char(3));
  writeInt(&b, 1);
  writeInt(&b, volume.nx);
  writeInt(&b, volume.ny);
  writeInt(&b, volume.nz);
  writeInt(&b, 1);
  for (int a = 0; a < 3; ++a) writeFloat(&b, volume.boundsMin[a]);
  for (int a = 0; a < 3; ++a) writeFloat(&b, volume.boundsMax[a]);
  for (float v : volume.values) writeFloat(&b, v);
  return b;
}

}  // namespace farm
