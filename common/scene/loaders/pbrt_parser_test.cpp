// pbrt's grammar apart from the scene it describes: what a target receives, and the errors that
// name the file and line without any scene built. The loader's own tests (pbrt_loader_test.cpp)
// cover what the directives mean.
#include "common/scene/loaders/pbrt_parser.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

// Keeps every directive it is handed, and the includes.
class Recorder : public PbrtTarget {
 public:
  void directive(PbrtDirective& d) override { directives.push_back(d); }
  void included(const PbrtDirective& d) override { includes.push_back(d.name); }
  std::vector<PbrtDirective> directives;
  std::vector<std::string> includes;
};

Recorder parse(const TempDir& dir, const std::string& text) {
  Recorder r;
  const std::string path = dir.write("scene.pbrt", text);
  parsePbrt(path, text, &r);
  return r;
}

// The error parsing `text` throws: its line and problem.
SceneLoadError parseError(const std::string& text) {
  TempDir dir("pbrt_parser_test");
  return thrownLoadError([&] { parse(dir, text); }, "no error for: " + text);
}

TEST(PbrtParser, HandsOverDirectivesWithTheirWordsNumbersAndParameters) {
  TempDir dir("pbrt_parser_test");
  Recorder r = parse(dir,
                     "LookAt 0 0 5  0 0 0  0 1 0\n"
                     "Transform [ 1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1 ]\n"
                     "Shape \"sphere\" \"float radius\" 2 \"color Kd\" [0.5 0.25 1]\n"
                     "  \"point P\" [0 0 0] \"bool flag\" true\n");
  ASSERT_EQ(r.directives.size(), 3u);
  EXPECT_EQ(r.directives[0].name, "LookAt");
  EXPECT_EQ(r.directives[0].numbers.size(), 9u);
  EXPECT_EQ(r.directives[1].numbers.size(), 16u);
  PbrtDirective& shape = r.directives[2];
  EXPECT_EQ(shape.line, 3);
  ASSERT_EQ(shape.strings.size(), 1u);
  EXPECT_EQ(shape.strings[0], "sphere");
  EXPECT_EQ(shape.getFloat("radius", 1), 2);
  EXPECT_EQ(shape.getFloat("missing", 7), 7);
  EXPECT_TRUE(shape.getBool("flag", false));
  // pbrt's synonyms read as their canonical types.
  ASSERT_NE(shape.typed("Kd", {"rgb"}), nullptr);
  EXPECT_EQ(shape.getNumbers("P", {"point3"}, 3).size(), 3u);
  EXPECT_EQ(shape.find("P")->line, 4);
  shape.rejectUnused("shape");  // every parameter read
}

TEST(PbrtParser, ResolvesIncludesBesideTheSceneAndTellsTheTarget) {
  TempDir dir("pbrt_parser_test");
  dir.write("parts/camera.pbrt", "Camera \"perspective\"\n");
  Recorder r = parse(dir, "Include \"parts/camera.pbrt\"\nWorldBegin\n");
  ASSERT_EQ(r.includes.size(), 1u);
  EXPECT_EQ(r.includes[0], "Include");
  ASSERT_EQ(r.directives.size(), 2u);
  EXPECT_EQ(r.directives[0].name, "Camera");
  EXPECT_NE(r.directives[0].file.find("camera.pbrt"), std::string::npos);
  EXPECT_EQ(r.directives[1].name, "WorldBegin");
}

TEST(PbrtParser, AnIncludeCycleIsAnError) {
  TempDir dir("pbrt_parser_test");
  dir.write("a.pbrt", "Include \"b.pbrt\"\n");
  dir.write("b.pbrt", "Include \"a.pbrt\"\n");
  const SceneLoadError e =
      thrownLoadError([&] { parse(dir, "Include \"a.pbrt\"\n"); }, "a cycle parsed");
  EXPECT_NE(e.problem().find("include cycle"), std::string::npos) << e.what();
}

TEST(PbrtParser, MalformedParameterListsNameTheirLine) {
  SceneLoadError twice = parseError("Shape \"sphere\"\n \"float radius\" 1\n \"float radius\" 2\n");
  EXPECT_EQ(twice.line(), 3);
  EXPECT_NE(twice.problem().find("given twice"), std::string::npos) << twice.what();
  SceneLoadError mixed = parseError("Shape \"sphere\" \"float radius\" [1 \"two\"]\n");
  EXPECT_NE(mixed.problem().find("mixes numbers and strings"), std::string::npos);
  SceneLoadError declaration = parseError("Shape \"sphere\" \"radius\" 1\n");
  EXPECT_NE(declaration.problem().find("not a parameter declaration"), std::string::npos);
  SceneLoadError unclosed = parseError("Shape \"sphere\" \"float radius\" [1 2\n");
  EXPECT_NE(unclosed.problem().find("expected ']'"), std::string::npos);
  SceneLoadError positional = parseError("Shape 3\n");
  EXPECT_NE(positional.problem().find("expects 1 quoted string"), std::string::npos);
}

TEST(PbrtParser, TypedAccessAndUnreadParametersAreErrorsOnTheirLine) {
  TempDir dir("pbrt_parser_test");
  Recorder r = parse(dir,
                     "Material \"diffuse\"\n"
                     "  \"string type\" \"a\"\n"
                     "  \"float sigma\" 0.5\n"
                     "  \"integer count\" 2.5\n");
  PbrtDirective& d = r.directives.at(0);
  const SceneLoadError type =
      thrownLoadError([&] { d.getInt("type", 0); }, "a string read as an integer");
  EXPECT_EQ(type.line(), 2);
  EXPECT_NE(type.problem().find("must be of type integer, not string"), std::string::npos);
  const SceneLoadError fraction =
      thrownLoadError([&] { d.getInt("count", 0); }, "2.5 read as an integer");
  EXPECT_EQ(fraction.line(), 4);
  const SceneLoadError unread =
      thrownLoadError([&] { d.rejectUnused("material 'diffuse'"); }, "'sigma' was never read");
  EXPECT_EQ(unread.line(), 3);
  EXPECT_EQ(unread.problem(), "material 'diffuse': parameter 'float sigma' is not supported");
}

}  // namespace
}  // namespace farm
