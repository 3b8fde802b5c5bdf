#include "common/scene/loaders/light_builders.h"

#include <cmath>

#include "common/scene/loaders/image_reader.h"
#include "common/scene/loaders/scene_files.h"

namespace farm {

namespace fs = std::filesystem;

PointLightDescription pointLight(const Vec3f& position, const Spectrum& intensity,
                                 const std::string& origin) {
  PointLightDescription light;
  light.position = position;
  light.intensity = intensity;
  light.origin = origin;
  return light;
}

void aimSpot(PointLightDescription* light, const Vec3f& axis, double totalDegrees,
             double falloffStartDegrees, PointLightDescription::Falloff falloff) {
  light->spot = true;
  light->direction = normalize(axis);
  light->cosTotalWidth = float(std::cos(totalDegrees * M_PI / 180));
  light->cosFalloffStart = float(std::cos(falloffStartDegrees * M_PI / 180));
  light->falloff = falloff;
}

EnvironmentDescription makeEnvironment(const fs::path& dir, const std::string& file, int line,
                                       const Spectrum& scale, const Matrix4& lightToWorld,
                                       const std::string& filename, bool equalAreaAllowed) {
  EnvironmentDescription e;
  e.present = true;
  e.origin = fs::path(file).filename().string() + ":" + std::to_string(line) + " (environment" +
             (filename.empty() ? "" : " " + filename) + ")";
  if (!isFinite(scale) || !(scale.x >= 0 && scale.y >= 0 && scale.z >= 0))
    throw SceneLoadError(file, line, "environment radiance must be finite and >= 0");
  e.scale = scale;
  double unused;
  if (!lightToWorld.isFinite() || similarityOf(lightToWorld, &unused) != Similarity::Uniform)
    throw SceneLoadError(file, line,
                         "the environment's transformation must be a rotation (a non-uniform "
                         "scale or a shear would distort its directions)");
  e.toWorld = lightToWorld;
  if (filename.empty()) return e;
  const fs::path path = sceneFilePath(dir, filename, "environment map", file, line);
  const std::string bytes = readSceneFile(path, "environment map '" + filename + "'", file, line);
  std::shared_ptr<TextureImage> image;
  try {
    image = readTextureImage(bytes, filename, TextureEncoding::Automatic);
  } catch (const std::exception& x) {
    throw SceneLoadError(file, line, "cannot read environment map '" + filename + "': " + x.what());
  }
  if (equalAreaAllowed && image->width == image->height) {
    e.mapping = EnvironmentDescription::Mapping::EqualArea;
  } else if (image->width != 2 * image->height) {
    throw SceneLoadError(file, line,
                         "environment map '" + filename + "' is " + std::to_string(image->width) +
                             "x" + std::to_string(image->height) +
                             (equalAreaAllowed ? ": it must be a square equal-area map (pbrt-v4) "
                                                 "or a lat-long map twice as wide as high"
                                               : ": it must be a lat-long map, twice as wide as "
                                                 "high"));
  }
  e.image = std::move(image);
  return e;
}

}  // namespace farm
