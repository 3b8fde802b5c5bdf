#include "common/scene/texture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

namespace farm {
namespace {

// A 2x2 float image: top row red, green; bottom row blue, white (linear values).
std::shared_ptr<TextureImage> quad() {
  auto img = std::make_shared<TextureImage>();
  img->width = img->height = 2;
  img->floats = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  return img;
}

std::vector<TextureDescription> imageTextures(TextureWrap wrap) {
  TextureDescription t;
  t.type = TextureDescription::Type::Image;
  t.image = quad();
  t.wrap = wrap;
  return {t};
}

void expectSpectrum(const Spectrum& a, const Spectrum& b, float tol = 1e-6f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Texture, TexelCentresAndTheVerticalFlip) {
  auto t = imageTextures(TextureWrap::Clamp);
  // Texel centres at (i + 0.5) / 2; v = 0 is the image's bottom row.
  expectSpectrum(evalTexture(t, 0, {0.25f, 0.75f}), {1, 0, 0});  // top left
  expectSpectrum(evalTexture(t, 0, {0.75f, 0.75f}), {0, 1, 0});  // top right
  expectSpectrum(evalTexture(t, 0, {0.25f, 0.25f}), {0, 0, 1});  // bottom left
  expectSpectrum(evalTexture(t, 0, {0.75f, 0.25f}), {1, 1, 1});  // bottom right
}

TEST(Texture, BilinearBetweenCentres) {
  auto t = imageTextures(TextureWrap::Clamp);
  // Halfway between the top two centres, then the middle of all four.
  expectSpectrum(evalTexture(t, 0, {0.5f, 0.75f}), {0.5f, 0.5f, 0});
  expectSpectrum(evalTexture(t, 0, {0.5f, 0.5f}), {0.5f, 0.5f, 0.5f});
  // A quarter of the way from top left to top right.
  expectSpectrum(evalTexture(t, 0, {0.375f, 0.75f}), {0.75f, 0.25f, 0});
}

TEST(Texture, WrapModes) {
  // At u = 0 (the left edge, half a texel left of the first centre) repeat mixes in the right
  // column, clamp stays on the left one, black fades to zero.
  expectSpectrum(evalTexture(imageTextures(TextureWrap::Repeat), 0, {0.0f, 0.75f}),
                 {0.5f, 0.5f, 0});
  expectSpectrum(evalTexture(imageTextures(TextureWrap::Clamp), 0, {0.0f, 0.75f}), {1, 0, 0});
  expectSpectrum(evalTexture(imageTextures(TextureWrap::Black), 0, {0.0f, 0.75f}), {0.5f, 0, 0});
  // Repeat is periodic, far from the origin too.
  auto r = imageTextures(TextureWrap::Repeat);
  expectSpectrum(evalTexture(r, 0, {1000.25f, -99.25f}), evalTexture(r, 0, {0.25f, 0.75f}), 1e-3f);
  // Non-finite coordinates give black rather than a crash.
  expectSpectrum(evalTexture(r, 0, {NAN, 0.5f}), {0, 0, 0});
}

TEST(Texture, EightBitSrgbDecoding) {
  auto img = std::make_shared<TextureImage>();
  img->width = img->height = 1;
  img->bytes = {0, 188, 255};
  img->srgb = true;
  // sRGB 188/255 = 0.737 decodes to 0.5029 (IEC 61966-2-1).
  expectSpectrum(img->texel(0, 0), {0, 0.50289f, 1}, 1e-4f);
  img->srgb = false;
  expectSpectrum(img->texel(0, 0), {0, 188 / 255.0f, 1}, 1e-6f);
}

TEST(Texture, CheckerboardScaleAndMapping) {
  std::vector<TextureDescription> t(4);
  t[0].value = Spectrum(0.2f);
  t[1].value = Spectrum(0.8f);
  t[2].type = TextureDescription::Type::Checkerboard;
  t[2].tex1 = 0, t[2].tex2 = 1;
  t[2].uScale = t[2].vScale = 4;  // four squares across the unit square
  t[3].type = TextureDescription::Type::Scale;
  t[3].tex1 = 2, t[3].tex2 = 1;
  expectSpectrum(evalTexture(t, 2, {0.1f, 0.1f}), Spectrum(0.2f));   // (0, 0): even
  expectSpectrum(evalTexture(t, 2, {0.3f, 0.1f}), Spectrum(0.8f));   // (1, 0): odd
  expectSpectrum(evalTexture(t, 2, {0.3f, 0.3f}), Spectrum(0.2f));   // (1, 1): even
  expectSpectrum(evalTexture(t, 2, {-0.1f, 0.1f}), Spectrum(0.8f));  // (-1, 0): odd
  expectSpectrum(evalTexture(t, 3, {0.3f, 0.1f}), Spectrum(0.64f));
}

}  // namespace
}  // namespace farm
