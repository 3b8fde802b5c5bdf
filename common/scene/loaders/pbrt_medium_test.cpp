// pbrt's participating media: MakeNamedMedium (homogeneous, and density grids in pbrt-v3's and
// pbrt-v4's forms), MediumInterface for shapes and the camera, interface materials, and clear
// errors for what is not supported.
#include <gtest/gtest.h>

#include <string>

#include "common/scene/loaders/pbrt_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"
#include "common/scene/medium.h"

namespace farm {
namespace {

// The camera inside "fog" when `cameraInFog`; the first world line is line 7.
std::string scene(const std::string& world, bool cameraInFog = false) {
  return std::string(
             "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.2 "
             "0.3] \"rgb sigma_s\" [1 2 3] \"float scale\" 2 \"float g\" -0.4\n") +
         (cameraInFog ? "MediumInterface \"fog\" \"fog\"\n" : "\n") +
         "LookAt 0 0 0  0 0 1  0 1 0\n"
         "Camera \"perspective\" \"float fov\" [ 45 ]\n"
         "Film \"image\" \"integer xresolution\" [ 32 ] \"integer yresolution\" [ 16 ]\n"
         "WorldBegin\n" +
         world;
}

TEST(PbrtMedia, NamedMediaInterfacesAndTheCamera) {
  TempDir dir;
  const SceneDescription s = loadPbrtScene(dir.write("m.pbrt", scene(R"(
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" 2
AttributeEnd
AttributeBegin
  Translate 5 0 0
  MakeNamedMedium "smoke" "string type" "heterogeneous" "rgb sigma_a" [0 1 2]
      "rgb sigma_s" [3 2 1] "integer nx" 2 "integer ny" 1 "integer nz" 3
      "float density" [0 1 2 3 4 5] "point p0" [-1 -1 -1] "point p1" [1 1 1]
  MediumInterface "smoke" "fog"
  Material ""
  Shape "sphere"
AttributeEnd
MediumInterface "fog"
Shape "sphere" "float radius" 0.5
Shape "trianglemesh" "integer indices" [0 1 2] "point P" [0 0 0  1 0 0  0 1 0]
)",
                                                                     true)));
  ASSERT_EQ(s.media.size(), 2u);
  const MediumDescription& fog = s.media[0];
  EXPECT_EQ(fog.type, MediumDescription::Type::Homogeneous);
  EXPECT_NEAR(fog.sigmaA.z, 0.6f, 1e-6f);
  EXPECT_NEAR(fog.sigmaS.y, 4.0f, 1e-6f);
  EXPECT_FLOAT_EQ(fog.g, -0.4f);
  const MediumDescription& smoke = s.media[1];
  EXPECT_EQ(smoke.type, MediumDescription::Type::Grid);
  EXPECT_TRUE(smoke.cellCentred);
  EXPECT_EQ(smoke.nx * smoke.ny * smoke.nz, 6);
  // p0 and p1 in the space of the Translate: the grid's unit cube spans [4, 6] x [-1, 1]^2.
  const Vec3f lo = smoke.worldToGrid.applyPoint(Vec3f(4, -1, -1));
  const Vec3f hi = smoke.worldToGrid.applyPoint(Vec3f(6, 1, 1));
  EXPECT_NEAR(length(lo), 0, 1e-5f);
  EXPECT_NEAR(length(hi - Vec3f(1.0f)), 0, 1e-5f);
  EXPECT_EQ(s.camera.medium, 0);
  ASSERT_EQ(s.shapes.size(), 4u);
  EXPECT_TRUE(s.shapes[0].nullBoundary);
  EXPECT_TRUE(s.shapes[0].hasMediumInterface);
  EXPECT_EQ(s.shapes[0].interiorMedium, 0);
  EXPECT_EQ(s.shapes[0].exteriorMedium, -1);
  EXPECT_TRUE(s.shapes[1].nullBoundary);
  EXPECT_EQ(s.shapes[1].interiorMedium, 1);
  EXPECT_EQ(s.shapes[1].exteriorMedium, 0);
  // The same medium on both sides: pbrt leaves the ray's medium as it is.
  for (size_t i : {2u, 3u}) {
    EXPECT_FALSE(s.shapes[i].hasMediumInterface);
    EXPECT_FALSE(s.shapes[i].nullBoundary);
    EXPECT_GE(s.shapes[i].bsdf, 0);
  }
}

TEST(PbrtMedia, UnsupportedAndMalformedMediaAreClearErrors) {
  TempDir dir;
  struct Case {
    std::string world;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {"MakeNamedMedium \"c\" \"string type\" \"cloud\"\n", 7, "'cloud' is not supported"},
      {"MakeNamedMedium \"c\" \"rgb sigma_a\" [1 1 1]\n", 7, "has no \"string type\""},
      {"MakeNamedMedium \"c\" \"string type\" \"homogeneous\" \"string preset\" \"Skin1\"\n", 7,
       "named presets"},
      {"MakeNamedMedium \"c\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb "
       "sigma_s\" [1 1 1] \"rgb Le\" [1 1 1]\n",
       7, "emitting media"},
      {"MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb "
       "sigma_s\" [1 1 1]\n",
       7, "'fog' is defined twice"},
      {"MakeNamedMedium \"c\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb "
       "sigma_s\" [1 1 1] \"float g\" 1\n",
       7, "(-1, 1)"},
      {"MakeNamedMedium \"c\" \"string type\" \"uniformgrid\" \"rgb sigma_a\" [1 1 1] \"rgb "
       "sigma_s\" [1 1 1] \"integer nx\" 2 \"float density\" [1]\n",
       7, "has 1 values for nx * ny * nz = 2"},
      {"MakeNamedMedium \"c\" \"string type\" \"uniformgrid\" \"rgb sigma_a\" [1 2 1] \"rgb "
       "sigma_s\" [1 1 1] \"float density\" [1]\n",
       7, "same in every channel"},
      {"MakeNamedMedium \"c\" \"string type\" \"uniformgrid\" \"rgb sigma_a\" [1 1 1] \"rgb "
       "sigma_s\" [1 1 1] \"float density\" [1] \"point p1\" [0 1 1]\n",
       7, "the box from p0 to p1 is empty"},
      {"MediumInterface \"nowhere\" \"\"\nShape \"sphere\"\n", 8,
       "medium 'nowhere' is not defined"},
      {"Material \"interface\"\nAreaLightSource \"diffuse\"\nShape \"sphere\"\n", 9,
       "area light on an interface material"},
  };
  int k = 0;
  for (const Case& c : cases)
    expectLoadError(dir.write("bad" + std::to_string(k++) + ".pbrt", scene(c.world)), c.message,
                    c.line);
  // The camera's medium must exist once the file is read.
  expectLoadError(dir.write("camera.pbrt",
                            "MediumInterface \"air\" \"air\"\nCamera \"perspective\"\n"
                            "WorldBegin\nShape \"sphere\"\n"),
                  "the camera's medium 'air' is not defined", 2);
}

}  // namespace
}  // namespace farm
