#pragma once
// Mitsuba 0.6's binary grid volume (.vol, its gridvolume plugin): "VOL", version 3, encoding 1
// (float32), the resolution, the channel count, the bounding box, then the values with x
// varying fastest, all little-endian. What a heterogeneous medium's density comes from.
#include <string>
#include <vector>

#include "common/math/vec.h"

namespace farm {

struct GridVolume {
  int nx = 0, ny = 0, nz = 0;
  Vec3f boundsMin, boundsMax;  // the box the samples span, corner to corner
  std::vector<float> values;   // nx * ny * nz, channel 0 of the file
};

// Decodes a .vol file's bytes; on failure returns false and says why in *problem (truncated,
// not a VOL file, an encoding other than float32, more than 2^28 values, an empty box, values
// that are not finite).
bool decodeGridVolume(const std::string& bytes, GridVolume* out, std::string* problem);

// The bytes of a .vol file holding `volume` (one channel): for tests and tools.
std::string encodeGridVolume(const GridVolume& volume);

}  // namespace farm
