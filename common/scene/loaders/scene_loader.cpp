#include "common/scene/loaders/scene_loader.h"

#include <filesystem>

#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/loaders/pbrt_loader.h"

namespace farm {

SceneDescription loadSceneDescription(const std::string& path) {
  if (std::filesystem::path(path).extension() == ".pbrt") return loadPbrtScene(path);
  return loadMitsubaScene(path);
}

}  // namespace farm
