#include "common/scene/loaders/pbrt_loader.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/film/image.h"
#include "common/scene/camera.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kShared = FARM_SHARED_DIR;

void expectNear(const Vec3f& a, const Vec3f& b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// A camera at the origin looking down +z, then the world; the first world line is line 5.
std::string scene(const std::string& world, const std::string& header = "") {
  return "LookAt 0 0 0  0 0 1  0 1 0\n"
         "Camera \"perspective\" \"float fov\" [ 45 ]\n"
         "Film \"image\" \"integer xresolution\" [ 32 ] \"integer yresolution\" [ 16 ]\n" +
         header + "WorldBegin\n" + world;
}

const char* kTriangle =
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2] "
    "\"point P\" [0 0 0  1 0 0  0 1 0]\n";

// ---- The two published scenes ----

TEST(PbrtLoader, CornellBoxPbrtMatchesTheMitsubaScene) {
  SceneDescription p = loadSceneDescription(kShared + "/scenes/cornell-box-pbrt/scene.pbrt");
  SceneDescription m = loadSceneDescription(kShared + "/scenes/cornell-box/scene.xml");
  EXPECT_EQ(p.maxDepth, 6);  // maxdepth 5 bounces
  EXPECT_EQ(p.camera.width, 1024);
  EXPECT_EQ(p.camera.height, 1024);
  EXPECT_EQ(p.camera.filter, FilterType::Tent);
  EXPECT_FLOAT_EQ(p.camera.fovDegrees, m.camera.fovDegrees);
  // The same rays: the image's corners look the same way in both cameras.
  Camera cp(p.camera), cm(m.camera);
  for (Vec2f film : {Vec2f(0, 0), Vec2f(1024, 0), Vec2f(0, 1024), Vec2f(700, 300)}) {
    Ray a = cp.generateRay(film), b = cm.generateRay(film);
    expectNear(a.o, b.o, 1e-4f);
    expectNear(a.d, b.d, 1e-4f);
  }
  ASSERT_EQ(p.shapes.size(), 8u);
  int emitters = 0;
  for (const ShapeDescription& s : p.shapes) {
    if (!s.isEmitter) continue;
    ++emitters;
    expectNear(s.radiance, Spectrum(17, 12, 4), 0);
  }
  EXPECT_EQ(emitters, 1);
}

TEST(PbrtLoader, VeachAjarLoadsWithItsTexturesAndMaterials) {
  SceneDescription s = loadSceneDescription(kShared + "/scenes/veach-ajar/scene.pbrt");
  EXPECT_EQ(s.maxDepth, 14);
  EXPECT_EQ(s.camera.width, 512);
  EXPECT_EQ(s.camera.height, 288);
  ASSERT_EQ(s.textures.size(), 3u);
  for (const TextureDescription& t : s.textures) {
    ASSERT_EQ(t.type, TextureDescription::Type::Image);
    EXPECT_TRUE(t.image->srgb);  // 8-bit PNG: sRGB-encoded
  }
  EXPECT_EQ(s.textures[0].image->width, 1920);
  EXPECT_EQ(s.textures[0].image->height, 1280);
  int textured = 0, rough = 0, glass = 0;
  for (const BsdfDescription& b : s.bsdfs) {
    textured += b.reflectanceTexture >= 0;
    if (b.type == BsdfDescription::Type::RoughConductor) {
      ++rough;
      EXPECT_EQ(b.distribution, MicrofacetDistribution::GGX);
      EXPECT_TRUE(b.alpha == 0.25f || b.alpha == 0.1f || b.alpha == 0.15f) << b.alpha;
      expectNear(b.eta, Spectrum(1.65746f, 0.880369f, 0.521229f), 1e-6f);
    }
    glass += b.type == BsdfDescription::Type::Dielectric;
  }
  EXPECT_EQ(textured, 3);
  EXPECT_EQ(rough, 4);
  EXPECT_EQ(glass, 1);
  for (const ShapeDescription& sh : s.shapes) {
    if (s.bsdfs[size_t(sh.bsdf)].reflectanceTexture >= 0) {
      EXPECT_FALSE(sh.uvs.empty()) << sh.origin;
    }
  }
}

// The landscape picture's texture, seen through the loaded scene: a camera ray hits the
// picture, and the BSDF there has the image's colour at the hit's texture coordinates (sky at
// the top, land at the bottom), not a constant.
TEST(PbrtLoader, VeachAjarTextureLookupsFollowThePicture) {
  SceneDescription desc = loadSceneDescription(kShared + "/scenes/veach-ajar/scene.pbrt");
  Scene scene(desc);
  const Camera& cam = scene.camera();
  // The picture spans about y 62..118 of the 512 x 288 film (and x 155..280): average the
  // reflectance along a row near its top and one near its bottom.
  auto rowMean = [&](float y, Vec2f* uv) {
    Spectrum sum(0.0f);
    int n = 0;
    for (float x = 175; x <= 265; x += 5, ++n) {
      SurfaceHit hit;
      EXPECT_TRUE(scene.intersect(cam.generateRay({x, y}), &hit));
      const Bsdf bsdf = scene.bsdfAt(hit.shape, hit.uv);
      EXPECT_EQ(bsdf.reflectanceTexture(), 0) << "not the picture at " << x << ", " << y;
      // The lookup is the image's bilinear value at the hit's uv.
      expectNear(bsdf.reflectance(), evalTexture(desc.textures, 0, hit.uv), 1e-6f);
      sum += bsdf.reflectance();
      *uv = hit.uv;
    }
    return sum / float(n);
  };
  Vec2f uvTop, uvBottom;
  Spectrum sky = rowMean(66, &uvTop);
  Spectrum land = rowMean(112, &uvBottom);
  EXPECT_GT(uvTop.y, uvBottom.y);  // texture v grows upwards
  // Sky at the top is bluer than red; the yellow-green land at the bottom has little blue.
  EXPECT_GT(sky.z, 1.1f * sky.x) << sky.x << " " << sky.y << " " << sky.z;
  EXPECT_GT(land.y, 5 * land.z) << land.x << " " << land.y << " " << land.z;
}

// ---- Transforms and the camera ----

TEST(PbrtLoader, CameraLooksDownPlusZWithPlusXToTheRight) {
  TempDir dir;
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", scene(kTriangle)));
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_EQ(s.camera.height, 16);
  EXPECT_EQ(s.camera.fovAxis, FovAxis::Smaller);
  EXPECT_EQ(s.maxDepth, 6);  // pbrt's default path integrator: maxdepth 5
  Camera cam(s.camera);
  expectNear(cam.generateRay({16, 8}).d, {0, 0, 1}, 1e-6f);
  // pbrt's camera space is left-handed: with +y up and +z ahead, +x is the image's right.
  EXPECT_GT(cam.generateRay({31, 8}).d.x, 0.1f);
  EXPECT_GT(cam.generateRay({16, 0}).d.y, 0.1f);
  // fov 45 spans the shorter (vertical) axis.
  Ray top = cam.generateRay({16, 0});
  EXPECT_NEAR(top.d.y / top.d.z, std::tan(22.5 * M_PI / 180), 1e-5);
}

TEST(PbrtLoader, TransformsComposeAsPbrtDoes) {
  TempDir dir;
  std::string world =
      "AttributeBegin\n"
      "  Translate 1 0 0\n"
      "  Scale 2 2 2\n" +  // applies first: (1,0,0) -> (2,0,0) -> (3,0,0)
      std::string(kTriangle) +
      "AttributeEnd\n"
      "TransformBegin\n"
      "  Transform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n" +  // column by column
      kTriangle +
      "TransformEnd\n"
      "Rotate 90 0 0 1\n" +
      kTriangle + "Identity\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 -1 1]\n" + kTriangle;
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", scene(world)));
  ASSERT_EQ(s.shapes.size(), 4u);
  expectNear(s.shapes[0].positions[1], {3, 0, 0}, 1e-6f);
  expectNear(s.shapes[1].positions[0], {5, 6, 7}, 1e-6f);
  expectNear(s.shapes[2].positions[1], {0, 1, 0}, 1e-6f);  // after AttributeEnd, TransformEnd
  expectNear(s.shapes[3].positions[2], {0, 1, -1}, 1e-6f);
}

TEST(PbrtLoader, LookAtAndCoordinateSystems) {
  TempDir dir;
  std::string text =
      "LookAt 1 2 3  1 2 10  0 1 0\n"
      "Camera \"perspective\"\n"
      "WorldBegin\n"
      "CoordSysTransform \"camera\"\n" +
      std::string(kTriangle);
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", text));
  Camera cam(s.camera);
  expectNear(cam.position(), {1, 2, 3}, 1e-5f);
  expectNear(cam.forward(), {0, 0, 1}, 1e-6f);
  EXPECT_EQ(s.camera.width, 1280);  // pbrt's default film
  EXPECT_EQ(s.camera.height, 720);
  // In camera space the triangle sits at the eye.
  expectNear(s.shapes[0].positions[0], {1, 2, 3}, 1e-5f);
}

TEST(PbrtLoader, OrientationOfEmittersFollowsPbrt) {
  // Without normals the winding decides (counter-clockwise seen from +z here: emits to +z),
  // ReverseOrientation turns it round, and so does a mirroring transform; with normals the
  // normals decide.
  TempDir dir;
  std::string light = "AreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\n";
  std::string world = "AttributeBegin\n" + light + kTriangle + "AttributeEnd\n" +
                      "AttributeBegin\n" + light + "ReverseOrientation\n" + kTriangle +
                      "AttributeEnd\n" + "AttributeBegin\n" + light + "Scale 1 1 -1\n" + kTriangle +
                      "AttributeEnd\n" + "AttributeBegin\n" + light +
                      "ReverseOrientation\n"
                      "Shape \"trianglemesh\" \"integer indices\" [0 1 2] "
                      "\"point P\" [0 0 0  1 0 0  0 1 0] \"normal N\" [0 0 1 0 0 1 0 0 1]\n"
                      "AttributeEnd\n" +
                      kTriangle;
  SceneDescription desc = loadPbrtScene(dir.write("s.pbrt", scene(world)));
  ASSERT_EQ(desc.shapes.size(), 5u);
  // +z; reversed; mirrored (the plane z = 0 maps onto itself, but the mirror turns its normal
  // round, as it would any object's); with normals, which ReverseOrientation does not change.
  const float expected[4] = {1, -1, -1, 1};
  for (int i = 0; i < 4; ++i) {
    const ShapeDescription& s = desc.shapes[size_t(i)];
    EXPECT_TRUE(s.isEmitter);
    expectNear(s.radiance, {1, 2, 3}, 0);
    Vec3f n = cross(s.positions[s.indices[1]] - s.positions[s.indices[0]],
                    s.positions[s.indices[2]] - s.positions[s.indices[0]]);
    if (!s.normals.empty()) n = s.normals[s.indices[0]];
    EXPECT_EQ(n.z > 0 ? 1.0f : -1.0f, expected[i]) << "shape " << i;
  }
  EXPECT_FALSE(desc.shapes[4].isEmitter);  // outside the attribute block
}

// ---- Materials ----

TEST(PbrtLoader, MaterialsOfBothVersions) {
  TempDir dir;
  std::string world =
      "Material \"matte\" \"rgb Kd\" [0.1 0.2 0.3]\n" + std::string(kTriangle) +
      "Material \"diffuse\" \"rgb reflectance\" [0.4 0.5 0.6]\n" + kTriangle +
      // v3 metal: roughness remapped by the polynomial (0.1 -> 0.3954...)
      "Material \"metal\" \"float roughness\" 0.1\n" + kTriangle +
      // v4 conductor: remapped by the square root, named spectra
      "Material \"conductor\" \"float roughness\" 0.04 \"spectrum eta\" \"metal-Au-eta\" "
      "\"spectrum k\" \"metal-Au-k\"\n" +
      kTriangle + "Material \"conductor\"\n" + kTriangle +  // v4 default: smooth copper
      "Material \"glass\" \"float index\" 1.33\n" + kTriangle +
      "Material \"dielectric\" \"float roughness\" 0.09 \"bool remaproughness\" false\n" +
      kTriangle + "Material \"mirror\"\n" + kTriangle +
      "MakeNamedMaterial \"red\" \"string type\" \"matte\" \"rgb Kd\" [0.9 0 0]\n"
      "NamedMaterial \"red\"\n" +
      kTriangle +
      // v3 metal of roughness 0: remapped from its clamp 1e-3, so still rough (alpha 0.047)
      "Material \"metal\" \"float roughness\" 0\n" + kTriangle +
      "Material \"plastic\" \"rgb Kd\" [0.5 0.4 0.3] \"rgb Ks\" [0.2 0.2 0.2] "
      "\"float roughness\" 0.01 \"bool remaproughness\" false\n" +
      kTriangle;
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", scene(world)));
  ASSERT_EQ(s.shapes.size(), 11u);
  auto bsdf = [&](int shape) { return s.bsdfs[size_t(s.shapes[size_t(shape)].bsdf)]; };
  EXPECT_EQ(bsdf(0).type, BsdfDescription::Type::Diffuse);
  EXPECT_TRUE(bsdf(0).twoSided);
  expectNear(bsdf(0).reflectance, {0.1f, 0.2f, 0.3f}, 0);
  expectNear(bsdf(1).reflectance, {0.4f, 0.5f, 0.6f}, 0);
  EXPECT_EQ(bsdf(2).type, BsdfDescription::Type::RoughConductor);
  double x = std::log(0.1);
  double alphaV3 =
      1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x;
  EXPECT_NEAR(bsdf(2).alpha, alphaV3, 1e-6);
  expectNear(bsdf(2).eta, {0.2004377f, 0.9240334f, 1.102212f}, 1e-6f);  // copper by default
  EXPECT_EQ(bsdf(3).type, BsdfDescription::Type::RoughConductor);
  EXPECT_NEAR(bsdf(3).alpha, 0.2, 1e-7);
  expectNear(bsdf(3).eta, {0.1431189557f, 0.3749570432f, 1.4424785571f}, 1e-7f);
  expectNear(bsdf(3).k, {3.9831604247f, 2.3857207478f, 1.6032152899f}, 1e-7f);
  EXPECT_EQ(bsdf(4).type, BsdfDescription::Type::Conductor);
  EXPECT_EQ(bsdf(5).type, BsdfDescription::Type::Dielectric);
  EXPECT_FLOAT_EQ(bsdf(5).intIOR, 1.33f);
  EXPECT_FLOAT_EQ(bsdf(5).extIOR, 1.0f);
  EXPECT_EQ(bsdf(6).type, BsdfDescription::Type::RoughDielectric);
  EXPECT_FLOAT_EQ(bsdf(6).alpha, 0.09f);
  EXPECT_FLOAT_EQ(bsdf(6).intIOR, 1.5f);
  EXPECT_EQ(bsdf(7).type, BsdfDescription::Type::Conductor);
  expectNear(bsdf(7).specularReflectance, Spectrum(0.9f), 0);
  expectNear(bsdf(8).reflectance, {0.9f, 0, 0}, 0);
  EXPECT_EQ(bsdf(9).type, BsdfDescription::Type::RoughConductor);
  EXPECT_NEAR(bsdf(9).alpha, 0.04718, 1e-4);
  EXPECT_EQ(bsdf(10).type, BsdfDescription::Type::Plastic);
  expectNear(bsdf(10).reflectance, {0.5f, 0.4f, 0.3f}, 0);
  expectNear(bsdf(10).specularReflectance, Spectrum(0.2f), 0);
  EXPECT_FLOAT_EQ(bsdf(10).alpha, 0.01f);
  EXPECT_FLOAT_EQ(bsdf(10).intIOR, 1.5f);
}

// pbrt-v4's coateddiffuse: the coated diffuse with v4's defaults (reflectance 0.5, eta 1.5, a
// smooth coat, made a microfacet coat of alpha 1e-4), the square-root roughness remapping, the
// series of the base's inter-reflections (nonlinear), and a warning that says what differs from
// pbrt's random walk.
TEST(PbrtLoader, CoatedDiffuse) {
  TempDir dir;
  SceneDescription s = loadPbrtScene(dir.write(
      "s.pbrt", scene("Material \"coateddiffuse\"\n"
                      "Shape \"sphere\"\n"
                      "Material \"coateddiffuse\" \"rgb reflectance\" [0.1 0.2 0.3] \"float "
                      "roughness\" 0.04 \"float eta\" 1.33 \"float thickness\" 0.1\n"
                      "Shape \"sphere\"\n")));
  ASSERT_EQ(s.bsdfs.size(), 2u);
  const BsdfDescription &smooth = s.bsdfs[0], &rough = s.bsdfs[1];
  EXPECT_EQ(smooth.type, BsdfDescription::Type::CoatedDiffuse);
  EXPECT_FLOAT_EQ(smooth.alpha, 1e-4f);
  EXPECT_FLOAT_EQ(smooth.intIOR, 1.5f);
  expectNear(smooth.reflectance, Spectrum(0.5f), 0);
  EXPECT_TRUE(smooth.nonlinear);
  EXPECT_TRUE(smooth.twoSided);
  ASSERT_TRUE(smooth.coating);
  EXPECT_EQ(rough.distribution, MicrofacetDistribution::GGX);
  EXPECT_FLOAT_EQ(rough.alpha, 0.2f);  // sqrt(0.04)
  EXPECT_FLOAT_EQ(rough.intIOR, 1.33f);
  expectNear(rough.reflectance, {0.1f, 0.2f, 0.3f}, 0);
  ASSERT_TRUE(rough.coating);
  ASSERT_EQ(s.warnings.size(), 2u);
  EXPECT_NE(s.warnings[0].find("roughness 1e-4"), std::string::npos) << s.warnings[0];
  EXPECT_NE(s.warnings[1].find("of thickness 0.1, does"), std::string::npos) << s.warnings[1];
}

TEST(PbrtLoader, ImageTexturesAndTheirEncodings) {
  TempDir dir;
  Image img(2, 1);
  img.set(0, 0, {0.5f, 0.25f, 1});
  img.set(1, 0, {0, 0, 0});
  std::string error;
  fs::create_directories(dir.path() / "tex");
  ASSERT_TRUE(writePreview((dir.path() / "tex" / "a.png").string(), img, &error)) << error;
  ASSERT_TRUE(writeExr((dir.path() / "tex" / "b.exr").string(), img, {}, &error)) << error;
  std::string world =
      "Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/a.png\"\n"
      "Texture \"lin\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/a.png\" "
      "\"bool gamma\" false\n"
      "Texture \"b\" \"spectrum\" \"imagemap\" \"string filename\" \"tex/b.exr\" "
      "\"float scale\" 2\n"
      "Texture \"unused\" \"spectrum\" \"imagemap\" \"string filename\" \"missing.png\"\n"
      "Material \"matte\" \"texture Kd\" \"a\"\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0  1 0 0  0 1 0] "
      "\"float uv\" [0.25 0.5  0.25 0.5  0.25 0.5]\n"
      "Material \"matte\" \"texture Kd\" \"lin\"\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0  1 0 0  0 1 0] "
      "\"point2 uv\" [0.25 0.5  0.25 0.5  0.25 0.5]\n"
      "Material \"diffuse\" \"texture reflectance\" \"b\"\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point P\" [0 0 0  1 0 0  0 1 0] "
      "\"point2 uv\" [0.25 0.5  0.25 0.5  0.25 0.5]\n";
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", scene(world)));
  Scene sc(s);
  // The preview stores sRGB bytes; decoded they are the linear values to 8-bit precision.
  Spectrum a = sc.bsdfAt(0, {0.25f, 0.5f}).reflectance();
  expectNear(a, {0.5f, 0.25f, 1}, 0.005f);
  // Read as linear, the same bytes are the sRGB-encoded values: brighter.
  Spectrum lin = sc.bsdfAt(1, {0.25f, 0.5f}).reflectance();
  EXPECT_NEAR(lin.x, 0.7354f, 0.005f);
  EXPECT_NEAR(lin.y, 0.5371f, 0.005f);
  // The EXR is linear floats, exact, times its scale.
  expectNear(sc.bsdfAt(2, {0.25f, 0.5f}).reflectance(), {1, 0.5f, 2}, 1e-6f);
  // Between the two texels, halfway: bilinear.
  expectNear(sc.bsdfAt(2, {0.5f, 0.5f}).reflectance(), {0.5f, 0.25f, 1}, 1e-6f);
}

TEST(PbrtLoader, IncludeAndPlyMeshes) {
  TempDir dir;
  dir.write("mesh.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nproperty float u\nproperty float v\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n"
            "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n");
  dir.write("parts/geometry.pbrt", "Shape \"plymesh\" \"string filename\" \"mesh.ply\"\n");
  SceneDescription s = loadPbrtScene(
      dir.write("s.pbrt", scene("Translate 0 0 5\nInclude \"parts/geometry.pbrt\"\n")));
  ASSERT_EQ(s.shapes.size(), 1u);
  expectNear(s.shapes[0].positions[1], {1, 0, 5}, 1e-6f);
  ASSERT_EQ(s.shapes[0].uvs.size(), 3u);
  EXPECT_FLOAT_EQ(s.shapes[0].uvs[2].y, 1.0f);  // as the file has it
  EXPECT_TRUE(s.shapes[0].faceNormals);         // pbrt shades a mesh without normals flat
}

// ---- Errors: each names the file, the line and what is wrong ----

struct BadScene {
  std::string world;  // the first world line is line 5
  int line;
  std::string message;
};

TEST(PbrtLoader, UnsupportedAndMalformedInputGetsAClearError) {
  const BadScene cases[] = {
      {"LightSource \"goniometric\" \"rgb I\" [1 1 1]\n", 5,
       "light source 'goniometric' is not supported"},
      {"\n\nShape \"curve\" \"point P\" [0 0 0 1 1 1 2 2 2 3 3 3]\n", 7,
       "shape 'curve' is not supported"},
      {"Material \"coateddiffuse\" \"rgb albedo\" [0.5 0.5 0.5]\n", 5, "a scattering coat"},
      {"Material \"coateddiffuse\" \"spectrum eta\" \"glass-BK7\"\n", 5, "dispersive"},
      {"Material \"coateddiffuse\" \"rgb reflectance\" [1.5 0.5 0.5]\n", 5, "above 1"},
      {"Material \"plastic\" \"float roughness\" 0 \"bool remaproughness\" false\n", 5,
       "plastic of roughness 0"},
      {"Material \"uber\"\n", 5, "material 'uber' is not supported"},
      {"Material \"matte\" \"float sigma\" 20\n", 5, "Oren-Nayar"},
      {"Material \"matte\" \"rgb Kd\" [0.5 0.5]\n", 5, "takes 3 numbers"},
      {"Material \"matte\" \"rgb Kd\" [0.5 -0.5 0.5]\n", 5, "negative"},
      {"Material \"matte\" \"rgb Kx\" [0.5 0.5 0.5]\n", 5, "parameter 'rgb Kx' is not supported"},
      {"Material \"metal\" \"spectrum eta\" \"spds/Cu.eta.spd\"\n", 5, "not supported"},
      {"Material \"metal\" \"float uroughness\" 0.1 \"float vroughness\" 0.2\n", 5,
       "anisotropic roughness"},
      {"Material \"glass\" \"rgb Kt\" [0.5 1 1]\n", 5, "tinted glass"},
      {"Material \"matte\" \"texture bumpmap\" \"b\"\n", 5, "bump"},
      {"NamedMaterial \"nothing\"\n", 5, "named material 'nothing' is not defined"},
      {"Material \"matte\" \"texture Kd\" \"nothing\"\n", 5, "texture 'nothing' is not defined"},
      {"Texture \"t\" \"spectrum\" \"marble\"\nMaterial \"matte\" \"texture Kd\" \"t\"\n", 5,
       "texture class 'marble' is not supported"},
      {"Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"/etc/passwd.png\"\n"
       "Material \"matte\" \"texture Kd\" \"t\"\n",
       5, "outside the scene's folder"},
      {"Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"missing.png\"\n"
       "Material \"matte\" \"texture Kd\" \"t\"\n",
       5, "texture 'missing.png' not found"},
      {"Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"junk.png\"\n"
       "Material \"matte\" \"texture Kd\" \"t\"\n",
       5, "cannot read texture 'junk.png'"},
      {"Texture \"t\" \"spectrum\" \"checkerboard\"\nMaterial \"matte\" \"texture Kd\" \"t\"\n"
       "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n",
       7, "textured material but no uv"},
      {"Shape \"plymesh\" \"string filename\" \"../outside.ply\"\n", 5,
       "outside the scene's folder"},
      {"Shape \"plymesh\" \"string filename\" \"missing.ply\"\n", 5, "not found"},
      {"Shape \"plymesh\" \"string filename\" \"junk.png\"\n", 5, "cannot read PLY"},
      {"Shape \"trianglemesh\" \"integer indices\" [0 1 3] \"point P\" [0 0 0 1 0 0 0 1 0]\n", 5,
       "index 3 is not one of the 3 vertices"},
      {"Shape \"trianglemesh\" \"integer indices\" [0 1] \"point P\" [0 0 0 1 0 0 0 1 0]\n", 5,
       "multiple of 3"},
      {"Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"float alpha\" 0.5\n", 5,
       "alpha cut-outs"},
      {"Shape \"sphere\" \"float zmax\" 0.5\n", 5, "partial spheres"},
      {"Scale 1 2 1\nShape \"sphere\"\n", 6, "non-uniform scale"},
      {"AreaLightSource \"diffuse\" \"blackbody L\" [6500]\n", 5, "blackbody"},
      {"MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n", 5,
       "needs \"rgb sigma_a\" and \"rgb sigma_s\""},
      {"ObjectInstance \"o\"\n", 5, "object 'o' is not defined"},
      {"ObjectEnd\n", 5, "ObjectEnd without ObjectBegin"},
      {"ObjectBegin \"o\"\nAttributeEnd\n", 6, "AttributeEnd would end the definition"},
      {"ObjectBegin \"o\"\nAttributeBegin\nObjectEnd\n", 7, "ObjectEnd inside an AttributeBegin"},
      {"ObjectBegin \"o\"\n" + std::string(kTriangle) +
           "ObjectEnd\nScale 1 1 0\nObjectInstance \"o\"\n",
       9, "the instance's transformation is singular"},
      {"ObjectBegin \"o\"\nObjectBegin \"p\"\n", 6, "ObjectBegin inside the definition"},
      {"ObjectBegin \"o\"\nAreaLightSource \"diffuse\"\n" + std::string(kTriangle), 7,
       "area light inside an object definition"},
      {"AttributeEnd\n", 5, "AttributeEnd without AttributeBegin"},
      {"TransformEnd\n", 5, "TransformEnd without TransformBegin"},
      {"Rotate 30 0 0 0\n", 5, "zero axis"},
      {"Translate 1 2\n", 5, "takes 3 numbers"},
      {"Scale 0 0 0\nShape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0]\n", 6,
       "contains only degenerate triangles"},
      {"Camera \"perspective\"\n", 5, "must come before WorldBegin"},
      {"Frobnicate 1 2 3\n", 5, "unknown directive 'Frobnicate'"},
      {"Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2] "
       "\"integer indices\" [0 1 2]\n",
       5, "given twice"},
      {"Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 nan]\n", 5, "unexpected 'nan'"},
      {"Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 1e999]\n", 5, "not a finite number"},
      {"Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 1 0\n", 5, "expected ']'"},
      {"Shape \"trianglemesh \"point P\" [0 0 0 1 0 0 0 1 0]\n", 5, "unterminated string"},
      {"Shape \"trianglemesh\" \"P\" [0 0 0 1 0 0 0 1 0]\n", 5, "not a parameter declaration"},
      {"Shape \"trianglemesh\" \"float P\" [0 0 0 1 0 0 0 1 0]\n", 5, "must be of type point3"},
      {"Include \"loop.pbrt\"\n", 1, "includes itself (an include cycle)"},
      {"Include \"deep0.pbrt\"\n", 1, "nested deeper than 16 files"},
      // Textures name only textures defined before them (as in pbrt); the error is told
      // where a material uses one.
      {"Texture \"a\" \"spectrum\" \"scale\" \"texture tex1\" \"b\"\n"
       "Texture \"b\" \"spectrum\" \"constant\"\n"
       "Material \"matte\" \"texture Kd\" \"a\"\n",
       5, "texture 'b' is not defined"},
      {"Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"junk.tif\"\n"
       "Material \"matte\" \"texture Kd\" \"t\"\n",
       5, "not a texture format"},
      {"Translate 1e39 0 0\n", 5, "beyond the range of float"},
      {"Material \"metal\" \"rgb eta\" [1 1 3.5e38] \"rgb k\" [1 1 1]\n", 5,
       "beyond the range of float"},
      {"Include \"../elsewhere.pbrt\"\n", 5, "outside the scene's folder"},
      {"", 0, "the scene has no shapes"},
  };
  for (const BadScene& c : cases) {
    TempDir dir;
    dir.write("junk.png", "this is not an image");
    dir.write("loop.pbrt", "Include \"loop.pbrt\"\n");
    dir.write("junk.tif", "this is not an image");
    for (int k = 0; k < 20; ++k)
      dir.write("deep" + std::to_string(k) + ".pbrt",
                "Include \"deep" + std::to_string(k + 1) + ".pbrt\"\n");
    std::string path = dir.write("s.pbrt", scene(c.world));
    std::string error = loadError(path);
    const std::string place = c.line > 0 ? ":" + std::to_string(c.line) + ": " : std::string(": ");
    EXPECT_NE(error.find(place), std::string::npos) << c.world << " -> " << error;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.world << " -> " << error;
  }
}

TEST(PbrtLoader, HeaderErrors) {
  const BadScene cases[] = {
      {"Camera \"orthographic\"\n", 4, "camera 'orthographic' is not supported"},
      {"Camera \"perspective\" \"float lensradius\" -0.1\n", 4, "lensradius must be >= 0"},
      {"Camera \"perspective\" \"float focaldistance\" 0\n", 4, "focaldistance must be > 0"},
      {"PixelFilter \"mitchell\"\n", 4, "pixel filter 'mitchell' is not supported"},
      {"PixelFilter \"gaussian\" \"float xwidth\" 2 \"float ywidth\" 1\n", 4,
       "different x and y radii"},
      {"PixelFilter \"gaussian\" \"float xwidth\" 0.3 \"float ywidth\" 0.3\n", 4,
       "radius must be in [0.5, 16]"},
      {"PixelFilter \"gaussian\" \"float alpha\" 1000\n", 4, "alpha must be in [0.01, 100]"},
      {"PixelFilter \"triangle\"\n", 4, "radius 1 only"},  // v3's default radius is 2
      {"Film \"image\" \"float cropwindow\" [0 0.5 0 0.5]\n", 4, "cropwindow"},
      {"Film \"image\" \"integer xresolution\" 0\n", 4, "outside 1..65536"},
      {"Film \"image\" \"integer xresolution\" 65536 \"integer yresolution\" 65536\n", 4,
       "more than 2^28 pixels"},
      {"Integrator \"ambientocclusion\"\n", 4, "integrator 'ambientocclusion' is not supported"},
      {"Integrator \"path\" \"integer maxdepth\" -1\n", 4, "maxdepth must be >= 0"},
  };
  for (const BadScene& c : cases) {
    TempDir dir;
    std::string text = "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nFilm \"image\"\n";
    if (c.world.rfind("Camera", 0) == 0) text = "LookAt 0 0 0  0 0 1  0 1 0\n\n\n";
    text += c.world + "WorldBegin\n" + kTriangle;
    std::string error = loadError(dir.write("s.pbrt", text));
    EXPECT_NE(error.find(":" + std::to_string(c.line) + ": "), std::string::npos)
        << c.world << " -> " << error;
    EXPECT_NE(error.find(c.message), std::string::npos) << c.world << " -> " << error;
  }
  TempDir dir;
  EXPECT_NE(
      loadError(dir.write("s.pbrt", "WorldBegin\n" + std::string(kTriangle))).find("no Camera"),
      std::string::npos);
  EXPECT_NE(loadError(dir.write("t.pbrt", "Camera \"perspective\"\n")).find("no WorldBegin"),
            std::string::npos);
  EXPECT_NE(loadError((dir.path() / "missing.pbrt").string()).find("scene file not found"),
            std::string::npos);
}

TEST(PbrtLoader, HostileInputIsRefusedCheaply) {
  TempDir dir;
  // Scale textures nested 40 deep: evaluation would double per level with both children the
  // same, and a long chain would exhaust the stack.
  std::string world = "Texture \"t0\" \"spectrum\" \"constant\"\n";
  for (int k = 1; k <= 40; ++k)
    world += "Texture \"t" + std::to_string(k) + "\" \"spectrum\" \"scale\" \"texture tex1\" \"t" +
             std::to_string(k - 1) + "\" \"texture tex2\" \"t" + std::to_string(k - 1) + "\"\n";
  world += "Material \"matte\" \"texture Kd\" \"t40\"\n";
  EXPECT_NE(loadError(dir.write("deep.pbrt", scene(world))).find("nested deeper than 16"),
            std::string::npos);
  // A NUL inside a string (a path that the check and the open would read differently).
  std::string nul = "Shape \"plymesh\" \"string filename\" \"a";
  nul += '\0';
  nul += "/../../x.ply\"\n";
  EXPECT_NE(loadError(dir.write("nul.pbrt", scene(nul))).find("NUL"), std::string::npos);
  // A camera whose transformation stretches one axis.
  EXPECT_NE(loadError(dir.write("scaled.pbrt", "Scale 1 2 1\nCamera \"perspective\"\nWorldBegin\n" +
                                                   std::string(kTriangle)))
                .find("non-uniform scale"),
            std::string::npos);
}

// Instances are flattened: each ObjectInstance copies the object's shapes (as their definition's
// transformation placed them) through the transformation current at the instance.
TEST(PbrtLoader, ObjectInstancesAreFlattened) {
  TempDir dir;
  std::string world =
      "ObjectBegin \"tri\"\nTranslate 0 0 1\nMaterial \"matte\" \"rgb Kd\" [0.2 0.3 0.4]\n" +
      std::string(kTriangle) +
      "ObjectEnd\n"
      "Translate 10 0 0\nObjectInstance \"tri\"\n"
      "Scale -1 1 1\nObjectInstance \"tri\"\n";
  SceneDescription s = loadPbrtScene(dir.write("s.pbrt", scene(world)));
  ASSERT_EQ(s.shapes.size(), 2u);
  expectNear(s.shapes[0].positions[1], {11, 0, 1}, 1e-6f);
  expectNear(s.shapes[1].positions[1], {9, 0, 1}, 1e-6f);
  for (const ShapeDescription& sh : s.shapes) {
    // The material of the definition; the normal +z in both (the mirror in x leaves it).
    expectNear(s.bsdfs[size_t(sh.bsdf)].reflectance, {0.2f, 0.3f, 0.4f}, 0);
    Vec3f n = cross(sh.positions[sh.indices[1]] - sh.positions[sh.indices[0]],
                    sh.positions[sh.indices[2]] - sh.positions[sh.indices[0]]);
    EXPECT_GT(n.z, 0) << sh.origin;
  }
  // A sphere instanced through a mirror keeps its outside (the normal transformation keeps
  // normals on their side), as in pbrt.
  SceneDescription sp = loadPbrtScene(
      dir.write("sp.pbrt", scene("ObjectBegin \"ball\"\nShape \"sphere\"\nObjectEnd\n"
                                 "Translate 0 0 5\nScale -1 1 1\nObjectInstance \"ball\"\n")));
  ASSERT_EQ(sp.shapes.size(), 1u);
  EXPECT_FALSE(sp.shapes[0].flipNormals);
  expectNear(sp.shapes[0].center, {0, 0, 5}, 1e-6f);
  // The ObjectEnd ended the definition's attribute block: the Translate 0 0 1 stayed inside.
  EXPECT_NE(s.shapes[1].origin.find("instanced at s.pbrt:"), std::string::npos);
}

TEST(PbrtLoader, GaussianFilters) {
  TempDir dir;
  auto filterOf = [&](const std::string& header, const std::string& world = kTriangle) {
    return loadPbrtScene(dir.write("s.pbrt", scene(world, header))).camera;
  };
  CameraDescription v3 = filterOf("PixelFilter \"gaussian\"\n");  // v3: radius 2, alpha 2
  EXPECT_EQ(v3.filter, FilterType::Gaussian);
  EXPECT_FLOAT_EQ(v3.filterRadius, 2);
  EXPECT_FLOAT_EQ(v3.filterAlpha, 2);
  CameraDescription v4 = filterOf("PixelFilter \"gaussian\" \"float sigma\" 0.25\n");
  EXPECT_FLOAT_EQ(v4.filterRadius, 1.5f);  // v4's default radius
  EXPECT_FLOAT_EQ(v4.filterAlpha, 8);      // 1 / (2 sigma^2)
  // No PixelFilter: v3's box, unless the file is v4 (its default is a gaussian).
  EXPECT_EQ(filterOf("").filter, FilterType::Box);
  CameraDescription implicit = filterOf("", "Material \"diffuse\"\n" + std::string(kTriangle));
  EXPECT_EQ(implicit.filter, FilterType::Gaussian);
  EXPECT_FLOAT_EQ(implicit.filterRadius, 1.5f);
  EXPECT_FLOAT_EQ(implicit.filterAlpha, 2);
  // A parameterless gaussian in a v4 file: v4's radius, which only the materials tell.
  CameraDescription late =
      filterOf("PixelFilter \"gaussian\"\n", "Material \"diffuse\"\n" + std::string(kTriangle));
  EXPECT_FLOAT_EQ(late.filterRadius, 1.5f);
}

TEST(PbrtLoader, WarningsSayWhatWasIgnored) {
  TempDir dir;
  SceneDescription s =
      loadPbrtScene(dir.write("s.pbrt", scene(kTriangle,
                                              "Sampler \"halton\" \"integer pixelsamples\" 16\n"
                                              "Integrator \"bdpt\" \"integer maxdepth\" 9 "
                                              "\"bool visualizestrategies\" false\n")));
  EXPECT_EQ(s.maxDepth, 10);
  ASSERT_EQ(s.warnings.size(), 2u);
  EXPECT_NE(s.warnings[0].find("s.pbrt:4: Sampler 'halton' ignored"), std::string::npos);
  EXPECT_NE(s.warnings[1].find("visualizestrategies"), std::string::npos);
}

}  // namespace
}  // namespace farm
