#pragma once
// Texture images (PNG, JPEG, OpenEXR, and whatever else OpenImageIO reads) from a file's bytes:
// the only translation unit of the scene code that sees OpenImageIO's headers (they break
// protobuf's when included before them; see common/film/image.h).
#include <memory>
#include <string>

#include "common/scene/texture.h"

namespace farm {

enum class TextureEncoding {
  Automatic,  // eight- and sixteen-bit integers are sRGB-encoded, floats linear (pbrt's default)
  SRGB,
  Linear,
};

// The image in `bytes`, its format told by `name`'s extension; RGB (grey is replicated, alpha
// dropped). Throws std::runtime_error with OpenImageIO's reason, or ours (no pixels, more than
// 2^28 texels, a non-finite texel), when it cannot be used.
std::shared_ptr<TextureImage> readTextureImage(const std::string& bytes, const std::string& name,
                                               TextureEncoding encoding);

}  // namespace farm
