#include "common/scene/texture.h"

#include <array>
#include <cmath>

namespace farm {

namespace {

const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) {
      double v = i / 255.0;
      t[size_t(i)] = float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
    }
    return t;
  }();
  return table;
}

// Texel index along one axis of n texels, or -1 for Black outside.
int wrapIndex(int i, int n, TextureWrap wrap) {
  if (i >= 0 && i < n) return i;
  switch (wrap) {
    case TextureWrap::Repeat: {
      int m = i % n;
      return m < 0 ? m + n : m;
    }
    case TextureWrap::Clamp:
      return i < 0 ? 0 : n - 1;
    case TextureWrap::Black:
      return -1;
  }
  return -1;
}

Spectrum lookupImage(const TextureDescription& t, const Vec2f& st) {
  const TextureImage& img = *t.image;
  // Continuous texel coordinates with texel centres at i + 0.5; the row flips (see the header).
  double x = double(st.x) * img.width - 0.5;
  double y = (1.0 - double(st.y)) * img.height - 0.5;
  if (!std::isfinite(x) || !std::isfinite(y)) return Spectrum(0.0f);
  // Bring large coordinates near the image first, so that int conversion cannot overflow.
  if (t.wrap == TextureWrap::Repeat) {
    x -= img.width * std::floor(x / img.width);
    y -= img.height * std::floor(y / img.height);
  } else {
    x = std::fmin(std::fmax(x, -2.0), img.width + 1.0);
    y = std::fmin(std::fmax(y, -2.0), img.height + 1.0);
  }
  const double fx = std::floor(x), fy = std::floor(y);
  const float dx = float(x - fx), dy = float(y - fy);
  const int x0 = int(fx), y0 = int(fy);
  auto at = [&](int xi, int yi) {
    int a = wrapIndex(xi, img.width, t.wrap), b = wrapIndex(yi, img.height, t.wrap);
    return a < 0 || b < 0 ? Spectrum(0.0f) : img.texel(a, b);
  };
  return at(x0, y0) * ((1 - dx) * (1 - dy)) + at(x0 + 1, y0) * (dx * (1 - dy)) +
         at(x0, y0 + 1) * ((1 - dx) * dy) + at(x0 + 1, y0 + 1) * (dx * dy);
}

}  // namespace

Spectrum TextureImage::texel(int x, int y) const {
  const size_t i = (size_t(y) * size_t(width) + size_t(x)) * 3;
  if (!bytes.empty()) {
    if (srgb) {
      const auto& lut = srgbTable();
      return Spectrum(lut[bytes[i]], lut[bytes[i + 1]], lut[bytes[i + 2]]);
    }
    return Spectrum(bytes[i] / 255.0f, bytes[i + 1] / 255.0f, bytes[i + 2] / 255.0f);
  }
  return Spectrum(floats[i], floats[i + 1], floats[i + 2]);
}

Spectrum evalTexture(const std::vector<TextureDescription>& textures, int index, const Vec2f& uv) {
  const TextureDescription& t = textures[size_t(index)];
  const Vec2f st(t.uScale * uv.x + t.uOffset, t.vScale * uv.y + t.vOffset);
  switch (t.type) {
    case TextureDescription::Type::Constant:
      return t.value;
    case TextureDescription::Type::Image:
      return lookupImage(t, st);
    case TextureDescription::Type::Checkerboard: {
      if (!std::isfinite(st.x) || !std::isfinite(st.y)) return Spectrum(0.0f);
      const bool even = std::fmod(std::floor(double(st.x)) + std::floor(double(st.y)), 2.0) == 0;
      return evalTexture(textures, even ? t.tex1 : t.tex2, uv);
    }
    case TextureDescription::Type::Scale:
      return evalTexture(textures, t.tex1, uv) * evalTexture(textures, t.tex2, uv);
  }
  return Spectrum(0.0f);
}

}  // namespace farm
