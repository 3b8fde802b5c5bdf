// Mitsuba's bitmap textures: which texel a surface point sees, through every shape that carries
// texture coordinates (rectangle, OBJ with and without flipTexCoords, PLY), and their errors.
#include <gtest/gtest.h>

#include <string>

#include "common/film/image.h"
#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/loaders/scene_files.h"
#include "common/scene/loaders/temp_dir_for_tests.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const Spectrum kRed{1, 0, 0}, kGreen{0, 1, 0}, kBlue{0, 0, 1}, kWhite{1, 1, 1};

// A 2x2 image, as written: red top left, green top right, blue bottom left, white bottom right.
void writeQuadrants(const TempDir& dir, const std::string& name) {
  Image img(2, 2);
  img.set(0, 0, kRed);
  img.set(1, 0, kGreen);
  img.set(0, 1, kBlue);
  img.set(1, 1, kWhite);
  std::string error;
  fs::create_directories((dir.path() / name).parent_path());
  ASSERT_TRUE(writePreview((dir.path() / name).string(), img, &error)) << error;
}

std::string sceneXml(const std::string& body) {
  return "<scene version=\"0.5.0\">\n"
         "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" "
         "value=\"4\"/><integer name=\"height\" value=\"4\"/></film></sensor>\n" +
         body + "</scene>\n";
}

// The reflectance seen where a ray straight down -z meets the scene above (x, y).
Spectrum reflectanceAt(const Scene& scene, float x, float y) {
  Ray ray{{x, y, 5}, {0, 0, -1}};
  SurfaceHit hit;
  if (!scene.intersect(ray, &hit)) return Spectrum(-1.0f);
  return scene.bsdfAt(hit.shape, hit.uv).reflectance();
}

void expectColor(const Spectrum& got, const Spectrum& want, const std::string& where) {
  EXPECT_NEAR(got.x, want.x, 0.01f) << where;
  EXPECT_NEAR(got.y, want.y, 0.01f) << where;
  EXPECT_NEAR(got.z, want.z, 0.01f) << where;
}

// A unit square quad over [-1, 1]^2 at z = 0 in OBJ form, vt (0, 0) at (-1, -1).
const char* kObjQuad =
    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "f 1/1 2/2 3/3\nf 3/3 4/4 1/1\n";
const char* kPlyQuad =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    "property float z\nproperty float u\nproperty float v\nelement face 2\n"
    "property list uchar int vertex_indices\nend_header\n"
    "-1 -1 0 0 0\n1 -1 0 1 0\n1 1 0 1 1\n-1 1 0 0 1\n3 0 1 2\n3 2 3 0\n";

const char* kBitmap =
    "<texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" "
    "value=\"tex/q.png\"/></texture>";

std::string texturedShape(const std::string& type, const std::string& params) {
  return "<shape type=\"" + type + "\">" + params + "<bsdf type=\"diffuse\">" + kBitmap +
         "</bsdf></shape>\n";
}

// Mitsuba looks up row v of a bitmap from the image's top; the rectangle's (u, v) is
// ((x + 1) / 2, (y + 1) / 2); OBJ files' v is flipped unless flipTexCoords is false; PLY files'
// is taken as it is. So the quadrant each shape shows at (-0.5, -0.5) is known.
TEST(MitsubaTexture, EachShapeShowsTheTexelMitsubaWould) {
  TempDir dir;
  writeQuadrants(dir, "tex/q.png");
  dir.write("quad.obj", kObjQuad);
  dir.write("quad.ply", kPlyQuad);
  struct Case {
    std::string shape;
    Spectrum lowerLeft, lowerRight, upperLeft;  // at (-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5)
  };
  const Case cases[] = {
      {texturedShape("rectangle", ""), kRed, kGreen, kBlue},
      {texturedShape("obj", "<string name=\"filename\" value=\"quad.obj\"/>"), kBlue, kWhite, kRed},
      {texturedShape("obj",
                     "<string name=\"filename\" value=\"quad.obj\"/>"
                     "<boolean name=\"flipTexCoords\" value=\"false\"/>"),
       kRed, kGreen, kBlue},
      {texturedShape("ply", "<string name=\"filename\" value=\"quad.ply\"/>"), kRed, kGreen, kBlue},
  };
  for (const Case& c : cases) {
    Scene scene(loadMitsubaScene(dir.write("s.xml", sceneXml(c.shape))));
    expectColor(reflectanceAt(scene, -0.5f, -0.5f), c.lowerLeft, c.shape);
    expectColor(reflectanceAt(scene, 0.5f, -0.5f), c.lowerRight, c.shape);
    expectColor(reflectanceAt(scene, -0.5f, 0.5f), c.upperLeft, c.shape);
  }
}

// uscale, voffset and friends act on Mitsuba's (u, v); a top-level texture is shared by <ref>;
// gamma 1 reads the PNG's bytes as linear values.
TEST(MitsubaTexture, MappingReferencesAndGamma) {
  TempDir dir;
  writeQuadrants(dir, "tex/q.png");
  Image grey(1, 1);
  grey.set(0, 0, Spectrum(0.5f));
  std::string error;
  ASSERT_TRUE(writePreview((dir.path() / "tex" / "g.png").string(), grey, &error)) << error;
  // uscale 3 takes the rectangle's u = 0.25 to 0.75 (the right column) and 0.75 to 2.25 (the
  // left); voffset 0.5 takes v = 0.25 to 0.75 (the bottom row) and 0.75 to 1.25 (the top).
  const std::string body =
      "<texture type=\"bitmap\" id=\"shifted\"><string name=\"filename\" value=\"tex/q.png\"/>"
      "<float name=\"voffset\" value=\"0.5\"/><float name=\"uscale\" value=\"3\"/>"
      "</texture>\n"
      "<shape type=\"rectangle\"><bsdf type=\"diffuse\"><ref name=\"reflectance\" "
      "id=\"shifted\"/></bsdf></shape>\n"
      "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate x=\"5\"/></transform>"
      "<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"><string "
      "name=\"filename\" value=\"tex/g.png\"/><float name=\"gamma\" value=\"1\"/></texture>"
      "</bsdf></shape>\n"
      // clamped: voffset -0.5 takes v = 0.25 to -0.25, clamped to the top row
      "<shape type=\"rectangle\"><transform name=\"toWorld\"><translate x=\"-5\"/></transform>"
      "<bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"><string "
      "name=\"filename\" value=\"tex/q.png\"/><string name=\"wrapMode\" value=\"clamp\"/>"
      "<float name=\"voffset\" value=\"-0.5\"/></texture></bsdf></shape>\n";
  SceneDescription desc = loadMitsubaScene(dir.write("s.xml", sceneXml(body)));
  EXPECT_EQ(desc.textures.size(), 3u);
  Scene scene(desc);
  expectColor(reflectanceAt(scene, -0.5f, -0.5f), kWhite, "u 0.75, v 0.75");
  expectColor(reflectanceAt(scene, 0.5f, -0.5f), kBlue, "u 2.25, v 0.75");
  expectColor(reflectanceAt(scene, -0.5f, 0.5f), kGreen, "u 0.75, v 1.25");
  expectColor(reflectanceAt(scene, -5.5f, -0.5f), kRed, "clamped, u 0.25, v -0.25");
  // 0.5 is stored as its sRGB encoding, 0.7354; read as linear it stays that.
  expectColor(reflectanceAt(scene, 5, 0), Spectrum(0.7354f), "gamma 1");
}

TEST(MitsubaTexture, UnsupportedTexturesGetAClearError) {
  TempDir dir;
  writeQuadrants(dir, "tex/q.png");
  dir.write("bare.obj", "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nf 1 2 3\n");
  struct Bad {
    std::string body, message;
  };
  const std::string file = "<string name=\"filename\" value=\"tex/q.png\"/>";
  const Bad cases[] = {
      {"<texture type=\"checkerboard\" id=\"c\"/>", "unsupported texture type 'checkerboard'"},
      {"<texture type=\"bitmap\" id=\"t\"/>", "bitmap texture has no filename"},
      {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"missing.png\"/>"
       "</texture>",
       "texture 'missing.png' not found"},
      {"<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"../q.png\"/>"
       "</texture>",
       "is outside the scene's folder"},
      {"<texture type=\"bitmap\" id=\"t\">" + file +
           "<string name=\"wrapMode\" value=\"mirror\"/></texture>",
       "wrap mode 'mirror' is not supported"},
      {"<texture type=\"bitmap\" id=\"t\">" + file +
           "<float name=\"gamma\" value=\"2.2\"/></texture>",
       "gamma 2.2 is not supported"},
      {"<texture type=\"bitmap\" id=\"t\">" + file +
           "<string name=\"channel\" value=\"r\"/></texture>",
       "single-channel"},
      {"<texture type=\"bitmap\" id=\"t\">" + file + "<float name=\"blur\" value=\"1\"/></texture>",
       "unsupported parameter 'blur'"},
      {"<shape type=\"sphere\"><bsdf type=\"diffuse\">" + std::string(kBitmap) + "</bsdf></shape>",
       "a textured sphere is not supported"},
      {"<shape type=\"obj\"><string name=\"filename\" value=\"bare.obj\"/><bsdf "
       "type=\"diffuse\">" +
           std::string(kBitmap) + "</bsdf></shape>",
       "has a textured material but no texture coordinates"},
      {"<shape type=\"rectangle\"><bsdf type=\"conductor\"><texture type=\"bitmap\" "
       "name=\"specularReflectance\">" +
           file + "</texture></bsdf></shape>",
       "a textured 'specularReflectance' is not supported for bsdf type 'conductor'"},
      {"<bsdf type=\"diffuse\" id=\"d\"/><shape type=\"rectangle\"><bsdf type=\"diffuse\">"
       "<ref name=\"reflectance\" id=\"d\"/></bsdf></shape>",
       "names a <bsdf>"},
  };
  for (const Bad& c : cases) {
    const std::string path = dir.write("s.xml", sceneXml(c.body));
    expectLoadError(path, c.message, 3);
  }
}

}  // namespace
}  // namespace farm
