#pragma once
// A fresh directory for the loaders' tests to write small scene files into; removed with it.
// And the checks every loader error test makes.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/scene_loader.h"

namespace farm {

class TempDir {
 public:
  explicit TempDir(const std::string& tag = "scene_loader_test") {
    std::string pattern = (std::filesystem::temp_directory_path() / (tag + "_XXXXXX")).string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  // Writes `text` to `name` (creating its folders) and returns the file's path.
  std::string write(const std::string& name, const std::string& text) const {
    std::filesystem::path p = path_ / name;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// The SceneLoadError `run` throws; when it throws none, a test failure saying `unexpected` and an
// error of no line and no problem.
inline SceneLoadError thrownLoadError(const std::function<void()>& run,
                                      const std::string& unexpected) {
  try {
    run();
  } catch (const SceneLoadError& e) {
    return e;
  }
  ADD_FAILURE() << unexpected;
  return SceneLoadError("", 0, "");
}

// The SceneLoadError's message for the scene file at `path` (either format, by its extension),
// or "" when it loads.
inline std::string loadError(const std::string& path) {
  try {
    loadSceneDescription(path);
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "";
}

// That loading the scene at `path` fails at `line` with a message containing `message`.
inline void expectLoadError(const std::string& path, const std::string& message, int line) {
  try {
    loadSceneDescription(path);
    ADD_FAILURE() << "accepted a scene that should fail with: " << message;
  } catch (const SceneLoadError& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
        << e.what() << "\n  wanted: " << message;
    EXPECT_EQ(e.line(), line) << e.what();
  }
}

// That two spectra are the same, bit for bit (`what` names them).
inline void expectSameSpectrum(const Spectrum& a, const Spectrum& b, const std::string& what) {
  EXPECT_EQ(a.x, b.x) << what;
  EXPECT_EQ(a.y, b.y) << what;
  EXPECT_EQ(a.z, b.z) << what;
}

}  // namespace farm
