#pragma once
// What `farm submit` uploads: every file in the scene file's directory tree, each named by its
// SHA-256. Left out, with a warning: files over kMaxBundleFileBytes, and symbolic links that
// lead out of the tree (a bundle holds only what lies inside its folder: a link to
// ~/.ssh/id_rsa beside a scene must not travel to the farm).
#include <functional>
#include <string>
#include <vector>

#include "proto/bundle_manifest.h"

namespace farm {

struct LocalBundle {
  std::string root;                     // the scene file's directory
  std::string scenePath;                // the scene file, relative to root
  BundleManifest manifest;              // relative paths
  std::vector<std::string> localPaths;  // manifest[i] is read from localPaths[i]
  uint64_t totalBytes = 0;
};

// False (with *error) when the scene file does not exist or a file cannot be read. `warn` gets
// one line per file left out.
bool collectSceneBundle(const std::string& sceneFile, LocalBundle* bundle, std::string* error,
                        const std::function<void(const std::string&)>& warn = {});

}  // namespace farm
