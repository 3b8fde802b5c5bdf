#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "common/film/image.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kReferences = std::string(FARM_SHARED_DIR) + "/references/";

class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "image_io_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

std::vector<unsigned char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Image testImage(int w, int h) {
  Image img(w, h);
  for (size_t i = 0; i < img.rgb.size(); ++i)
    img.rgb[i] = float(std::sin(0.37 * double(i)) * std::pow(10.0, double(i % 7) - 3));
  img.rgb[0] = 0.0f;
  img.rgb[1] = 1e-30f;  // below half's range: float channels keep it
  img.rgb[2] = 3e6f;
  return img;
}

TEST_F(ImageIoTest, ExrRoundTripWithMetadata) {
  Image img = testImage(37, 21);
  ImageMetadata meta = {{"algorithm", "pssmlt"},
                        {"Z", "0.1234567890123"},
                        {"samples", "1e9"},
                        {"note", "with spaces, commas; and unicode \xc3\xa9"}};
  std::string error;
  ASSERT_TRUE(writeExr(path("a.exr"), img, meta, &error)) << error;
  Image back;
  ImageMetadata metaBack;
  ASSERT_TRUE(readExr(path("a.exr"), &back, &error, &metaBack)) << error;
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  ASSERT_EQ(back.rgb.size(), img.rgb.size());
  for (size_t i = 0; i < img.rgb.size(); ++i) ASSERT_EQ(back.rgb[i], img.rgb[i]) << i;
  for (const auto& [k, v] : meta) {
    ASSERT_TRUE(metaBack.count(k)) << k;
    EXPECT_EQ(metaBack[k], v);
  }
  // Reading without metadata works too, and no temporary file is left behind.
  ASSERT_TRUE(readExr(path("a.exr"), &back, &error)) << error;
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(ImageIoTest, ReadsReferences) {
  Image img;
  std::string error;
  ASSERT_TRUE(readExr(kReferences + "cornell-box-256.exr", &img, &error)) << error;
  EXPECT_EQ(img.width, 256);
  EXPECT_EQ(img.height, 256);
  EXPECT_EQ(img.rgb.size(), 256u * 256 * 3);
  double sum = 0;
  for (float v : img.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
  }
  EXPECT_GT(sum, 0);
  ASSERT_TRUE(readExr(kReferences + "veach-mis-320.exr", &img, &error)) << error;
  EXPECT_EQ(img.width, 320);
  EXPECT_EQ(img.height, 180);
}

TEST_F(ImageIoTest, ErrorsNameTheFile) {
  Image img;
  std::string error;
  EXPECT_FALSE(readExr(path("missing.exr"), &img, &error));
  EXPECT_NE(error.find(path("missing.exr")), std::string::npos) << error;

  std::ofstream(path("garbage.exr")) << "not an exr";
  EXPECT_FALSE(readExr(path("garbage.exr"), &img, &error));
  EXPECT_NE(error.find(path("garbage.exr")), std::string::npos) << error;

  std::string nowhere = path("no/such/dir/out.exr");
  EXPECT_FALSE(writeExr(nowhere, testImage(4, 4), {}, &error));
  EXPECT_NE(error.find(nowhere), std::string::npos) << error;
  EXPECT_FALSE(writePreview(path("no/such/dir/out.png"), testImage(4, 4), &error));
  EXPECT_NE(error.find(path("no/such/dir/out.png")), std::string::npos) << error;

  EXPECT_FALSE(writeExr(path("empty.exr"), Image(), {}, &error));
  EXPECT_NE(error.find(path("empty.exr")), std::string::npos) << error;
  // A standard attribute of another type cannot be overwritten by a string.
  EXPECT_FALSE(writeExr(path("reserved.exr"), testImage(4, 4), {{"compression", "x"}}, &error));
  EXPECT_NE(error.find("compression"), std::string::npos) << error;
  EXPECT_FALSE(writePreview(path("x.unknownformat"), testImage(4, 4), &error));
  EXPECT_NE(error.find(path("x.unknownformat")), std::string::npos) << error;
}

TEST_F(ImageIoTest, PngPreview) {
  std::string error;
  ASSERT_TRUE(writePreview(path("p.png"), testImage(33, 17), &error)) << error;
  std::vector<unsigned char> b = readBytes(path("p.png"));
  ASSERT_GT(b.size(), 24u);
  const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(b[i], signature[i]);
  auto be32 = [&](size_t at) {
    return uint32_t(b[at]) << 24 | uint32_t(b[at + 1]) << 16 | uint32_t(b[at + 2]) << 8 | b[at + 3];
  };
  EXPECT_EQ(be32(16), 33u);  // IHDR width
  EXPECT_EQ(be32(20), 17u);  // IHDR height
  EXPECT_EQ(b[24], 8);       // bit depth
}

// PPM is uncompressed, so the 8-bit sRGB values can be checked byte for byte.
TEST_F(ImageIoTest, PreviewIsClampedSrgb) {
  const float values[] = {0.0f,   1.0f,  2.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                          0.001f, 0.18f, 0.5f, 0.9f};
  Image img(3, 3);
  for (int i = 0; i < 9; ++i) img.set(i % 3, i / 3, Spectrum(values[i]));
  std::string error;
  ASSERT_TRUE(writePreview(path("p.ppm"), img, &error)) << error;
  std::vector<unsigned char> b = readBytes(path("p.ppm"));
  std::string text(b.begin(), b.end());
  std::istringstream header(text);
  std::string magic;
  int w = 0, h = 0, maxval = 0;
  header >> magic >> w >> h >> maxval;
  ASSERT_EQ(magic, "P6");
  ASSERT_EQ(w, 3);
  ASSERT_EQ(h, 3);
  ASSERT_EQ(maxval, 255);
  size_t start = size_t(header.tellg()) + 1;
  ASSERT_EQ(b.size(), start + 27);
  for (int i = 0; i < 9; ++i) {
    double v = std::isnan(values[i]) ? 0.0 : std::clamp(double(values[i]), 0.0, 1.0);
    double srgb = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    int expected = int(std::lround(srgb * 255));
    for (int c = 0; c < 3; ++c) EXPECT_EQ(b[start + 3 * i + c], expected) << values[i];
  }
}

}  // namespace
}  // namespace farm
