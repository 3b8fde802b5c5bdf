#include "cli/scene_bundle.h"

#include <algorithm>
#include <filesystem>

#include "proto/sha256.h"
#include "proto/wire_limits.h"

namespace farm {
namespace fs = std::filesystem;

bool collectSceneBundle(const std::string& sceneFile, LocalBundle* bundle, std::string* error,
                        const std::function<void(const std::string&)>& warn) {
  std::error_code ec;
  if (!fs::is_regular_file(sceneFile, ec)) {
    *error = "scene file '" + sceneFile + "' does not exist or is not a file";
    return false;
  }
  const fs::path scene = fs::absolute(sceneFile, ec);
  const fs::path root = scene.parent_path();
  bundle->root = root.string();
  bundle->scenePath = scene.filename().generic_string();

  std::vector<fs::path> files;
  for (fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec),
       end;
       it != end; it.increment(ec)) {
    if (ec) break;
    if (it->is_regular_file(ec)) files.push_back(it->path());
  }
  if (ec) {
    *error = "cannot list the scene directory '" + root.string() + "': " + ec.message();
    return false;
  }
  // Past the limits before anything is read: a scene file in a home directory would otherwise
  // hash the whole directory and then be refused by the coordinator.
  if (files.size() > kMaxBundleFiles) {
    *error = "the scene's folder '" + root.string() + "' holds more than " +
             std::to_string(kMaxBundleFiles) +
             " files, the limit of a scene bundle (every file under the scene's folder is "
             "sent): keep the scene and its meshes and textures in a folder of their own";
    return false;
  }
  std::sort(files.begin(), files.end());
  // Symbolic links are followed only to what lies inside the tree, judged by where they lead
  // after every link on the way is resolved.
  const fs::path canonicalRoot = fs::canonical(root, ec);
  if (ec) {
    *error = "cannot resolve the scene directory '" + root.string() + "': " + ec.message();
    return false;
  }
  for (const fs::path& file : files) {
    // Named by where it lies in the tree, not where a link leads (fs::relative would resolve
    // links and name a link after its target, twice in one manifest).
    const std::string relative = file.lexically_relative(root).generic_string();
    if (fs::is_symlink(file, ec)) {
      const fs::path target = fs::canonical(file, ec);
      const std::string inside = ec ? "" : fs::relative(target, canonicalRoot, ec).generic_string();
      if (ec || inside.empty() || inside == ".." || inside.rfind("../", 0) == 0) {
        if (warn) {
          warn("leaving out '" + relative + "': a symbolic link to '" + target.string() +
               "', outside the scene's folder");
        }
        continue;
      }
    }
    const uint64_t size = fs::file_size(file, ec);
    if (ec) continue;
    if (size > kMaxBundleFileBytes) {
      if (warn) {
        warn("leaving out '" + relative + "' (" + std::to_string(size >> 20) +
             " MiB, over the 256 MiB limit for bundle files)");
      }
      continue;
    }
    const std::string problem = checkRelativePath(relative);
    if (!problem.empty()) {
      if (warn) warn("leaving out a file: " + problem);
      continue;
    }
    if (bundle->totalBytes + size > kMaxBundleBytes) {
      *error = "the files under the scene's folder '" + root.string() + "' add up to more than " +
               std::to_string(kMaxBundleBytes >> 30) +
               " GiB, the limit of a scene bundle: keep the scene and its meshes and textures in "
               "a folder of their own";
      return false;
    }
    BundleEntry entry;
    entry.path = relative;
    if (!sha256File(file.string(), &entry.hash, &entry.size, error)) return false;
    bundle->totalBytes += entry.size;
    bundle->manifest.push_back(std::move(entry));
    bundle->localPaths.push_back(file.string());
  }
  return true;
}

}  // namespace farm
