// What `farm submit` collects from a scene's folder: everything inside it, and nothing that a
// symbolic link would bring in from outside.
#include "cli/scene_bundle.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "tests/test_support.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

TEST(SceneBundle, TakesTheFolderAndNoLinkOutOfIt) {
  testing::ScratchDir scratch("bundle");
  const fs::path scene = scratch / "scene", outside = scratch / "outside";
  fs::create_directories(scene / "meshes");
  fs::create_directories(outside);
  std::ofstream(scene / "scene.xml") << "<scene version=\"0.6.0\"/>\n";
  std::ofstream(scene / "meshes" / "a.obj") << "v 0 0 0\n";
  std::ofstream(outside / "secret.txt") << "not for the farm\n";
  fs::create_symlink(outside / "secret.txt", scene / "secret-link.txt");
  fs::create_symlink("../outside/secret.txt", scene / "relative-link.txt");
  fs::create_symlink("meshes/a.obj", scene / "inside-link.obj");
  fs::create_symlink(outside, scene / "outside-dir");

  LocalBundle bundle;
  std::string error;
  std::vector<std::string> warnings;
  ASSERT_TRUE(collectSceneBundle((scene / "scene.xml").string(), &bundle, &error,
                                 [&](const std::string& w) { warnings.push_back(w); }))
      << error;
  std::vector<std::string> paths;
  for (const BundleEntry& e : bundle.manifest) paths.push_back(e.path);
  EXPECT_EQ(paths, (std::vector<std::string>{"inside-link.obj", "meshes/a.obj", "scene.xml"}));
  ASSERT_EQ(warnings.size(), 2u);
  for (const std::string& w : warnings) {
    EXPECT_NE(w.find("outside the scene's folder"), std::string::npos) << w;
  }
  EXPECT_EQ(bundle.scenePath, "scene.xml");
}

}  // namespace
}  // namespace farm
