// The scene loaders on hostile files: the first byte picks the format (Mitsuba XML, pbrt, an
// OBJ mesh that a fixed Mitsuba scene names, a PLY mesh likewise), the rest is the file. A
// load error (std::exception with file and line) is the expected answer to nonsense.
#include <unistd.h>

#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/scene/loaders/scene_loader.h"
#include "fuzz/fuzz_target.h"

namespace {

// A directory of this process's own, removed at exit (held by a pointer that is never freed,
// so that it outlives the exit handler).
const std::string& scratch() {
  static const std::string* dir = [] {
    char pattern[] = "/tmp/farm-fuzz-scene-XXXXXX";
    if (!mkdtemp(pattern)) std::abort();
    auto* path = new std::string(pattern);
    std::atexit([] { std::filesystem::remove_all(scratch()); });
    return path;
  }();
  return *dir;
}

void write(const std::string& name, const std::string& bytes) {
  std::ofstream(scratch() + "/" + name, std::ios::binary | std::ios::trunc) << bytes;
}

std::string meshScene(const char* type, const char* file) {
  return std::string(
             "<scene version=\"0.6.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\">"
             "<integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/>"
             "</film></sensor><shape type=\"") +
         type + "\"><string name=\"filename\" value=\"" + file +
         "\"/></shape><shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" "
         "value=\"1\"/></emitter></shape></scene>";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (1 << 20)) return 0;
  const std::string body(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string scene;
  switch (data[0] % 4) {
    case 0:
      write("scene.xml", body);
      scene = "scene.xml";
      break;
    case 1:
      write("scene.pbrt", body);
      scene = "scene.pbrt";
      break;
    case 2:
      write("mesh.obj", body);
      write("obj.xml", meshScene("obj", "mesh.obj"));
      scene = "obj.xml";
      break;
    default:
      write("mesh.ply", body);
      write("ply.xml", meshScene("ply", "mesh.ply"));
      scene = "ply.xml";
      break;
  }
  try {
    farm::loadSceneDescription(scratch() + "/" + scene);
  } catch (const std::exception&) {
    // A clear error is the right answer.
  }
  return 0;
}
