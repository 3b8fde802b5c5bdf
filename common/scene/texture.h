#pragma once
// Textures: spatially varying reflectance, looked up by a surface point's (u, v). What pbrt's
// and Mitsuba's scenes use for albedo: an image (bilinear, wrapped), a checkerboard, a constant,
// and the product of two. Plain data in the description; evaluation is a pure function of it.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/math/vec.h"

namespace farm {

// A decoded image, row 0 at the top. Eight-bit images keep their bytes (a 4k texture in float
// would take 12 bytes a texel) and are decoded on lookup, through the sRGB curve when the file
// stores sRGB; all others are linear floats.
struct TextureImage {
  int width = 0, height = 0;
  std::vector<uint8_t> bytes;  // 3 per texel when eight-bit
  std::vector<float> floats;   // 3 per texel otherwise
  bool srgb = false;           // bytes are sRGB-encoded
  Spectrum texel(int x, int y) const;
};

enum class TextureWrap { Repeat, Clamp, Black };

struct TextureDescription {
  enum class Type { Constant, Image, Checkerboard, Scale };
  Type type = Type::Constant;
  Spectrum value{1.0f};                       // Constant
  std::shared_ptr<const TextureImage> image;  // Image
  TextureWrap wrap = TextureWrap::Repeat;     // Image
  // Checkerboard: tex1 on squares where floor(s) + floor(t) is even, tex2 elsewhere. Scale:
  // tex1 times tex2. Indices into the scene's textures, always smaller than this one's.
  int tex1 = -1, tex2 = -1;
  // The uv mapping: (s, t) = (uScale u + uOffset, vScale v + vOffset).
  float uScale = 1, vScale = 1, uOffset = 0, vOffset = 0;
  std::string origin;  // "scene.pbrt:12 (imagemap textures/wood.png)", for messages
};

// The value of texture `index` at texture coordinates uv. An image is looked up bilinearly
// between texel centres, with t = 0 at the image's bottom row (pbrt's and Mitsuba's
// convention: images are stored top row first, texture space has its origin at the bottom).
Spectrum evalTexture(const std::vector<TextureDescription>& textures, int index, const Vec2f& uv);

}  // namespace farm
