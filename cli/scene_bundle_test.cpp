// What `farm submit` collects from a scene's folder: everything inside it, and nothing that a
// symbolic link would bring in from outside.
#include "cli/scene_bundle.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "proto/wire_limits.h"
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

// A scene file dropped in a big folder (a home directory): refused before anything is hashed or
// sent, with a message that says what to do.
TEST(SceneBundle, AFolderPastTheBundleLimitsIsRefusedUpFront) {
  testing::ScratchDir scratch("bundle-limits");
  const fs::path folder = scratch / "home";
  fs::create_directories(folder / "photos");
  std::ofstream(folder / "scene.xml") << "<scene version=\"0.6.0\"/>\n";
  for (size_t i = 0; i < kMaxBundleFiles; ++i)
    std::ofstream(folder / "photos" / (std::to_string(i) + ".jpg"));
  LocalBundle bundle;
  std::string error;
  EXPECT_FALSE(collectSceneBundle((folder / "scene.xml").string(), &bundle, &error, nullptr));
  EXPECT_NE(error.find("more than 10000 files"), std::string::npos) << error;
  EXPECT_NE(error.find("a folder of their own"), std::string::npos) << error;
  // One file fewer is a bundle.
  fs::remove(folder / "photos" / "0.jpg");
  error.clear();
  EXPECT_TRUE(collectSceneBundle((folder / "scene.xml").string(), &bundle, &error, nullptr))
      << error;
  EXPECT_EQ(bundle.manifest.size(), kMaxBundleFiles);
}

}  // namespace
}  // namespace farm
