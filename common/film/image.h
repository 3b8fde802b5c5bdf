#pragma once
// A linear RGB float image and its file formats. Image I/O (OpenEXR, OpenImageIO) lives in
// image_io.cpp only: OpenImageIO headers must not meet protobuf's in one translation unit.
#include <map>
#include <string>
#include <vector>

#include "common/math/vec.h"

namespace farm {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // 3 floats per pixel, row-major, top row first

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3, 0.0f) {}
  Spectrum at(int x, int y) const {
    const float* p = &rgb[(size_t(y) * width + x) * 3];
    return {p[0], p[1], p[2]};
  }
  void set(int x, int y, const Spectrum& s) {
    float* p = &rgb[(size_t(y) * width + x) * 3];
    p[0] = s.x;
    p[1] = s.y;
    p[2] = s.z;
  }
};

// String attributes written into the EXR header (algorithm, Z, its error, samples, time, ...).
using ImageMetadata = std::map<std::string, std::string>;

// Each returns false and sets *error to a message naming the file when it fails.
bool writeExr(const std::string& path, const Image& image, const ImageMetadata& metadata,
              std::string* error);
bool readExr(const std::string& path, Image* image, std::string* error,
             ImageMetadata* metadata = nullptr);
// An 8-bit sRGB preview (clamped to [0,1], sRGB transfer curve), format from the extension.
bool writePreview(const std::string& path, const Image& image, std::string* error);

}  // namespace farm
