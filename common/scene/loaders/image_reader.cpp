#include "common/scene/loaders/image_reader.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iterator>
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
  // Only the formats textures come in: every other reader OpenImageIO has would be one more
  // parser of untrusted bytes in the coordinator.
  std::string extension = fs::path(name).extension().string();
  for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
  static const char* const kFormats[] = {".png", ".jpg", ".jpeg", ".exr", ".hdr", ".tga", ".pfm"};
  if (std::find(std::begin(kFormats), std::end(kFormats), extension) == std::end(kFormats))
    throw std::runtime_error("'" + extension +
                             "' is not a texture format (png, jpg, jpeg, exr, hdr, tga, pfm)");
  // The reader for the extension, fed from memory. Not ImageInput::open(name, config, proxy):
  // that one opens a file of that name on disk when there is one, proxy or not. The proxy is
  // declared first so that it outlives the reader, which closes through it.
  OIIO::Filesystem::IOMemReader reader(const_cast<char*>(bytes.data()), bytes.size());
  auto in = OIIO::ImageInput::create(extension.substr(1));
  if (!in) throw std::runtime_error("no reader for '" + extension + "' images");
  if (!in->supports("ioproxy"))
    throw std::runtime_error("'" + extension + "' images cannot be read from memory");
  in->set_ioproxy(&reader);
  OIIO::ImageSpec spec, config;
  // Colour as stored, not multiplied by alpha (pbrt reads RGB and ignores alpha).
  config.attribute("oiio:UnassociatedAlpha", 1);
  if (!in->open("memory" + extension, spec, config)) {
    std::string reason = in->geterror();
    throw std::runtime_error(reason.empty() ? "not a readable image" : reason);
  }
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw std::runtime_error("the image has no pixels");
  if (spec.depth > 1) throw std::runtime_error("volume images are not textures");
  if ((long long)spec.width * spec.height > kMaxTexels)
    throw std::runtime_error(std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                             " texels is over the limit of 2^28");
  // Grey (one or two channels: grey and alpha) is replicated; from three on, the first three
  // are RGB. Only those are read.
  const int read = spec.nchannels < 3 ? 1 : 3;
  const bool integer = spec.format.basetype == OIIO::TypeDesc::UINT8 ||
                       spec.format.basetype == OIIO::TypeDesc::UINT16;
  const bool srgb =
      encoding == TextureEncoding::SRGB || (encoding == TextureEncoding::Automatic && integer);
  auto image = std::make_shared<TextureImage>();
  image->width = spec.width;
  image->height = spec.height;
  const size_t texels = size_t(spec.width) * size_t(spec.height);
  if (spec.format.basetype == OIIO::TypeDesc::UINT8) {
    image->bytes.resize(texels * 3);
    if (!in->read_image(0, 0, 0, read, OIIO::TypeDesc::UINT8, image->bytes.data(), 3))
      throw std::runtime_error(in->geterror());
    if (read == 1)
      for (size_t i = 0; i < texels; ++i)
        image->bytes[3 * i + 1] = image->bytes[3 * i + 2] = image->bytes[3 * i];
    image->srgb = srgb;
    return image;
  }
  image->floats.resize(texels * 3);
  if (!in->read_image(0, 0, 0, read, OIIO::TypeDesc::FLOAT, image->floats.data(),
                      3 * sizeof(float)))
    throw std::runtime_error(in->geterror());
  for (size_t i = 0; i < texels; ++i) {
    if (read == 1) image->floats[3 * i + 1] = image->floats[3 * i + 2] = image->floats[3 * i];
    for (int c = 0; c < 3; ++c) {
      float& v = image->floats[3 * i + c];
      if (!std::isfinite(v) || v < 0)
        throw std::runtime_error("texel (" + std::to_string(i % spec.width) + ", " +
                                 std::to_string(i / spec.width) +
                                 ") is negative or not finite: not a reflectance");
      if (srgb) v = decodeSrgb(v);
    }
  }
  return image;
}

}  // namespace farm
