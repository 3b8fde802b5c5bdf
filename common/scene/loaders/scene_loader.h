#pragma once
// Any scene file the farm reads, by its extension: ".pbrt" (pbrt-v3 and v4) or Mitsuba 0.6 XML
// (".xml", and anything else, as before pbrt files were read).
#include <string>

#include "common/scene/loaders/scene_files.h"
#include "common/scene/scene_description.h"

namespace farm {

// Throws SceneLoadError for anything the loader cannot load faithfully.
SceneDescription loadSceneDescription(const std::string& path);

}  // namespace farm
