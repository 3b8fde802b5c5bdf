#include "common/scene/loaders/image_reader.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace farm {

namespace fs = std::filesystem;

namespace {
constexpr long long kMaxTexels = 1ll << 28;

float decodeSrgb(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
}  // namespace

std::shared_ptr<TextureImage> readTextureImage(const std::string& bytes, const std::string& name,
                                               TextureEncoding encoding) {
  // The reader for the name's extension, fed from memory. Not ImageInput::open(name, config,
  // proxy): that one opens a file of that name on disk when there is one, proxy or not.
  std::string extension = fs::path(name).extension().string();
  if (extension.size() < 2) throw std::runtime_error("no file extension to tell the format");
  auto in = OIIO::ImageInput::create(extension.substr(1));
  if (!in) throw std::runtime_error("no reader for '" + extension + "' images");
  if (!in->supports("ioproxy"))
    throw std::runtime_error("'" + extension + "' images cannot be read from memory");
  OIIO::Filesystem::IOMemReader reader(const_cast<char*>(bytes.data()), bytes.size());
  in->set_ioproxy(&reader);
  OIIO::ImageSpec spec;
  if (!in->open("memory" + extension, spec)) {
    std::string reason = in->geterror();
    throw std::runtime_error(reason.empty() ? "not a readable image" : reason);
  }
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw std::runtime_error("the image has no pixels");
  if (spec.depth > 1) throw std::runtime_error("volume images are not textures");
  if ((long long)spec.width * spec.height > kMaxTexels)
    throw std::runtime_error(std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                             " texels is over the limit of 2^28");
  const int channels = spec.nchannels;
  const bool integer = spec.format.basetype == OIIO::TypeDesc::UINT8 ||
                       spec.format.basetype == OIIO::TypeDesc::UINT16;
  const bool srgb =
      encoding == TextureEncoding::SRGB || (encoding == TextureEncoding::Automatic && integer);
  auto image = std::make_shared<TextureImage>();
  image->width = spec.width;
  image->height = spec.height;
  const size_t texels = size_t(spec.width) * size_t(spec.height);
  // Grey (one or two channels) is replicated; from three channels on, the first three are RGB.
  auto channelOf = [&](int c) { return channels < 3 ? 0 : c; };
  if (spec.format.basetype == OIIO::TypeDesc::UINT8) {
    std::vector<uint8_t> raw(texels * size_t(channels));
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, raw.data()))
      throw std::runtime_error(in->geterror());
    image->bytes.resize(texels * 3);
    for (size_t i = 0; i < texels; ++i)
      for (int c = 0; c < 3; ++c) image->bytes[3 * i + c] = raw[i * channels + channelOf(c)];
    image->srgb = srgb;
    return image;
  }
  std::vector<float> raw(texels * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, raw.data()))
    throw std::runtime_error(in->geterror());
  image->floats.resize(texels * 3);
  for (size_t i = 0; i < texels; ++i) {
    for (int c = 0; c < 3; ++c) {
      float v = raw[i * channels + channelOf(c)];
      if (!std::isfinite(v) || v < 0)
        throw std::runtime_error("texel (" + std::to_string(i % spec.width) + ", " +
                                 std::to_string(i / spec.width) +
                                 ") is negative or not finite: not a reflectance");
      image->floats[3 * i + c] = srgb ? decodeSrgb(v) : v;
    }
  }
  return image;
}

}  // namespace farm
