// The only translation unit that sees OpenEXR and OpenImageIO headers (see image.h for why).
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "common/film/image.h"

namespace farm {

namespace {

bool setError(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

bool validImage(const Image& image) {
  return image.width > 0 && image.height > 0 &&
         image.rgb.size() == size_t(image.width) * size_t(image.height) * 3;
}

// Writers go through a temporary file beside the target and rename it into place, so that a
// reader (a client polling for the image, a crash halfway) never sees half a file.
std::string temporaryPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

bool moveIntoPlace(const std::string& tmp, const std::string& path, std::string* error) {
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return setError(error, "cannot write '" + path + "': rename from temporary file failed");
  }
  return true;
}

float linearToSrgb(float v) {
  if (!(v > 0)) return 0.0f;  // NaN and negatives alike
  if (v >= 1) return 1.0f;
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

bool writeExr(const std::string& path, const Image& image, const ImageMetadata& metadata,
              std::string* error) {
  if (!validImage(image))
    return setError(error, "cannot write '" + path + "': image is empty or inconsistent (" +
                               std::to_string(image.width) + "x" + std::to_string(image.height) +
                               ", " + std::to_string(image.rgb.size()) + " floats)");
  std::string tmp = temporaryPathFor(path);
  try {
    Imf::Header header(image.width, image.height);
    // Full float: the image is an estimate whose relative error we measure; half would add 1e-3.
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& [key, value] : metadata) {
      if (key.empty()) return setError(error, "cannot write '" + path + "': empty metadata key");
      // A standard attribute of another type (compression, channels, ...) must not be replaced.
      auto existing = header.find(key);
      if (existing != header.end() &&
          !dynamic_cast<const Imf::StringAttribute*>(&existing.attribute()))
        return setError(error, "cannot write '" + path + "': metadata key '" + key +
                                   "' is a reserved OpenEXR attribute");
      header.insert(key, Imf::StringAttribute(value));
    }
    Imf::FrameBuffer fb;
    const size_t xStride = 3 * sizeof(float), yStride = xStride * size_t(image.width);
    // OpenEXR only reads from the frame buffer when writing.
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.rgb.data()));
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c)
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xStride, yStride));
    {
      Imf::OutputFile out(tmp.c_str(), header);
      out.setFrameBuffer(fb);
      out.writePixels(image.height);
    }
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    return setError(error, "cannot write '" + path + "': " + e.what());
  }
  return moveIntoPlace(tmp, path, error);
}

bool readExr(const std::string& path, Image* image, std::string* error, ImageMetadata* metadata) {
  try {
    Imf::InputFile in(path.c_str());
    const Imf::Header& header = in.header();
    const Imath::Box2i dw = header.dataWindow();
    const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536)
      return setError(error, "cannot read '" + path + "': unsupported data window " +
                                 std::to_string(w) + "x" + std::to_string(h));
    const Imf::ChannelList& channels = header.channels();
    bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
    bool luminance = !rgb && channels.findChannel("Y");
    if (!rgb && !luminance)
      return setError(error, "cannot read '" + path + "': no R, G, B (or Y) channels");

    Image result{static_cast<int>(w), static_cast<int>(h)};
    Imf::FrameBuffer fb;
    const size_t xStride = 3 * sizeof(float), yStride = xStride * size_t(w);
    char* base = reinterpret_cast<char*>(result.rgb.data());
    if (rgb) {
      const char* names[3] = {"R", "G", "B"};
      for (int c = 0; c < 3; ++c)
        fb.insert(names[c],
                  Imf::Slice::Make(Imf::FLOAT, base + c * sizeof(float), dw, xStride, yStride));
    } else {
      fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, base, dw, xStride, yStride));
    }
    in.setFrameBuffer(fb);
    in.readPixels(dw.min.y, dw.max.y);
    if (luminance)
      for (size_t i = 0; i < result.rgb.size(); i += 3)
        result.rgb[i + 1] = result.rgb[i + 2] = result.rgb[i];

    if (metadata) {
      metadata->clear();
      for (auto it = header.begin(); it != header.end(); ++it)
        if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute()))
          (*metadata)[it.name()] = s->value();
    }
    *image = std::move(result);
  } catch (const std::exception& e) {
    return setError(error, "cannot read '" + path + "': " + e.what());
  }
  return true;
}

bool writePreview(const std::string& path, const Image& image, std::string* error) {
  if (!validImage(image))
    return setError(error, "cannot write '" + path + "': image is empty or inconsistent");
  // The plugin is chosen from the real name; the pixels then go to a temporary name.
  auto out = OIIO::ImageOutput::create(path);
  if (!out) return setError(error, "cannot write '" + path + "': " + OIIO::geterror());
  std::vector<uint8_t> pixels(image.rgb.size());
  for (size_t i = 0; i < pixels.size(); ++i)
    pixels[i] = uint8_t(std::lround(linearToSrgb(image.rgb[i]) * 255.0f));
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  std::string tmp = temporaryPathFor(path);
  if (!out->open(tmp, spec)) {
    std::string message = out->geterror();
    std::remove(tmp.c_str());
    return setError(error, "cannot write '" + path + "': " + message);
  }
  bool ok = out->write_image(OIIO::TypeDesc::UINT8, pixels.data());
  std::string message = ok ? "" : out->geterror();
  if (!out->close() && ok) {
    ok = false;
    message = out->geterror();
  }
  if (!ok) {
    std::remove(tmp.c_str());
    return setError(error, "cannot write '" + path + "': " + message);
  }
  return moveIntoPlace(tmp, path, error);
}

}  // namespace farm
