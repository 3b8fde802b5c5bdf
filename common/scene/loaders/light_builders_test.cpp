// Lights from both formats (light_builders.h, its table). Environments: Mitsuba's constant and
// envmap (y up, u = atan2(x, -z) / 2 pi) and pbrt's infinite (z up, u = atan2(y, x) / 2 pi; v3's
// "mapname", v4's "filename"), each texel of a map found where its format puts it. Point and
// spot lights: position, intensity, axis, cone and each format's falloff. And their errors.
#include "common/scene/loaders/light_builders.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "common/film/image.h"
#include "common/sampling/warp.h"
#include "common/scene/environment_light.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

constexpr int kW = 8, kH = 4;

// A lat-long map whose texel (x, y) is (x + 1, y + 1, 1): every texel says where it is.
void writeMap(const TempDir& dir, const std::string& name, int w = kW, int h = kH) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, {float(x + 1), float(y + 1), 1});
  std::string error;
  ASSERT_TRUE(writeExr((dir.path() / name).string(), img, {}, &error)) << error;
}

const char* kMitsubaHead = R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
  </sensor>
  <shape type="sphere"><float name="radius" value="0.5"/></shape>
)";

std::string pbrtScene(const std::string& world) {
  return "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [ 45 ]\n"
         "Film \"image\" \"integer xresolution\" [ 8 ] \"integer yresolution\" [ 8 ]\n"
         "WorldBegin\nShape \"sphere\" \"float radius\" 0.5\n" +
         world;
}

// Every texel's centre, as a local direction of the given frame, looked up in the world.
template <typename LocalDirection>
void expectEveryTexel(const EnvironmentLight& light, const Matrix4& toWorld, float scale,
                      LocalDirection local) {
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const float theta = kPi * (y + 0.5f) / kH, phi = 2 * kPi * (x + 0.5f) / kW;
      const Spectrum L = light.radiance(normalize(toWorld.applyVector(local(theta, phi))));
      EXPECT_FLOAT_EQ(L.x, scale * (x + 1)) << "texel " << x << ", " << y;
      EXPECT_FLOAT_EQ(L.y, scale * (y + 1)) << "texel " << x << ", " << y;
    }
  }
}

TEST(EnvironmentLoader, MitsubaEnvmapIsYUp) {
  TempDir dir;
  writeMap(dir, "sky.exr");
  const std::string path = dir.write(
      "scene.xml", std::string(kMitsubaHead) +
                       "  <emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/>"
                       "<float name=\"scale\" value=\"2\"/>\n"
                       "    <transform name=\"toWorld\"><rotate x=\"1\" angle=\"30\"/></transform>"
                       "</emitter>\n</scene>\n");
  SceneDescription d = loadSceneDescription(path);
  ASSERT_TRUE(d.environment.present);
  EnvironmentLight light(d.environment);
  // Mitsuba: local (sin theta sin phi, cos theta, -sin theta cos phi).
  expectEveryTexel(light, Matrix4::rotate(Vec3f(1, 0, 0), 30), 2, [](float theta, float phi) {
    return Vec3f(std::sin(theta) * std::sin(phi), std::cos(theta),
                 -std::sin(theta) * std::cos(phi));
  });
}

TEST(EnvironmentLoader, PbrtInfiniteIsZUpInBothVersions) {
  for (const char* key : {"filename", "mapname"}) {
    TempDir dir;
    writeMap(dir, "sky.exr");
    const std::string path =
        dir.write("scene.pbrt", pbrtScene(std::string("AttributeBegin\nRotate 30 1 0 0\n") +
                                          "LightSource \"infinite\" \"string " + key +
                                          "\" \"sky.exr\" \"rgb L\" [3 3 3]\nAttributeEnd\n"));
    SceneDescription d = loadSceneDescription(path);
    ASSERT_TRUE(d.environment.present) << key;
    EnvironmentLight light(d.environment);
    // pbrt: local (sin theta cos phi, sin theta sin phi, cos theta).
    expectEveryTexel(light, Matrix4::rotate(Vec3f(1, 0, 0), 30), 3, [](float theta, float phi) {
      return Vec3f(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                   std::cos(theta));
    });
  }
}

// pbrt-v4's "filename" with a square map: the equal-area mapping, in the light's frame.
TEST(EnvironmentLoader, PbrtV4SquareMapIsEqualArea) {
  TempDir dir;
  writeMap(dir, "square.exr", 8, 8);
  SceneDescription d = loadSceneDescription(
      dir.write("scene.pbrt", pbrtScene("AttributeBegin\nRotate 30 1 0 0\nLightSource \"infinite\" "
                                        "\"string filename\" \"square.exr\"\nAttributeEnd\n")));
  ASSERT_TRUE(d.environment.present);
  EXPECT_EQ(d.environment.mapping, EnvironmentDescription::Mapping::EqualArea);
  const EnvironmentLight light(d.environment);
  // Every texel, looked up at its centre's direction in the light's frame turned to the world.
  const Matrix4 toWorld = Matrix4::rotate(Vec3f(1, 0, 0), 30);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      const Vec3f local = equalAreaSquareToSphere(Vec2f((x + 0.5f) / 8, (y + 0.5f) / 8));
      const Spectrum got = light.radiance(normalize(toWorld.applyVector(local)));
      const Spectrum want = d.environment.image->texel(x, y);
      EXPECT_TRUE(got.x == want.x && got.y == want.y && got.z == want.z) << x << " " << y;
    }
}

TEST(EnvironmentLoader, ConstantEnvironments) {
  TempDir dir;
  const std::string xml = dir.write(
      "scene.xml", std::string(kMitsubaHead) +
                       "  <emitter type=\"constant\"><rgb name=\"radiance\" value=\"1 2 3\"/>"
                       "</emitter>\n</scene>\n");
  const std::string pbrt =
      dir.write("scene.pbrt", pbrtScene("LightSource \"infinite\" \"rgb L\" [1 2 3]\n"));
  for (const std::string& path : {xml, pbrt}) {
    SceneDescription d = loadSceneDescription(path);
    ASSERT_TRUE(d.environment.present) << path;
    EXPECT_EQ(d.environment.image, nullptr);
    const Spectrum L = EnvironmentLight(d.environment).radiance(normalize(Vec3f(0.3f, -1, 2)));
    EXPECT_FLOAT_EQ(L.x, 1);
    EXPECT_FLOAT_EQ(L.y, 2);
    EXPECT_FLOAT_EQ(L.z, 3);
  }
}

void expectNear(const Vec3f& a, const Vec3f& b) {
  EXPECT_NEAR(a.x, b.x, 1e-5f);
  EXPECT_NEAR(a.y, b.y, 1e-5f);
  EXPECT_NEAR(a.z, b.z, 1e-5f);
}

TEST(PointLightLoader, PbrtPointAndSpot) {
  TempDir dir;
  const std::string spot =
      "LightSource \"spot\" \"rgb I\" [5 5 5] \"point from\" [0 4 0] \"point to\" [0 0 0] "
      "\"float coneangle\" 40 \"float conedeltaangle\" 10\n";
  const std::string world =
      "AttributeBegin\nTranslate 1 2 3\n"
      "LightSource \"point\" \"rgb I\" [1 2 3] \"float scale\" 2 \"point3 from\" [0 1 0]\n"
      "AttributeEnd\n" +
      spot;
  SceneDescription v3 = loadSceneDescription(dir.write("v3.pbrt", pbrtScene(world)));
  ASSERT_EQ(v3.pointLights.size(), 2u);
  const PointLightDescription& p = v3.pointLights[0];
  EXPECT_FALSE(p.spot);
  expectNear(p.position, Vec3f(1, 3, 3));
  expectNear(p.intensity, Vec3f(2, 4, 6));
  const PointLightDescription& s = v3.pointLights[1];
  EXPECT_TRUE(s.spot);
  expectNear(s.position, Vec3f(0, 4, 0));
  expectNear(s.direction, Vec3f(0, -1, 0));
  EXPECT_NEAR(s.cosTotalWidth, std::cos(40 * kPi / 180), 1e-6f);
  EXPECT_NEAR(s.cosFalloffStart, std::cos(30 * kPi / 180), 1e-6f);
  EXPECT_EQ(s.falloff, PointLightDescription::Falloff::PbrtV3Quartic);
  // A v4 file (its "diffuse" material says so): the same spot falls off by a smoothstep.
  SceneDescription v4 =
      loadSceneDescription(dir.write("v4.pbrt", pbrtScene("Material \"diffuse\"\n" + spot)));
  ASSERT_EQ(v4.pointLights.size(), 1u);
  EXPECT_EQ(v4.pointLights[0].falloff, PointLightDescription::Falloff::PbrtV4Smoothstep);
}

TEST(PointLightLoader, MitsubaPointAndSpot) {
  TempDir dir;
  const std::string path =
      dir.write("scene.xml",
                std::string(kMitsubaHead) +
                    "  <emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/>"
                    "<rgb name=\"intensity\" value=\"4 5 6\"/></emitter>\n"
                    "  <emitter type=\"spot\"><float name=\"cutoffAngle\" value=\"30\"/>"
                    "<rgb name=\"intensity\" value=\"7\"/>\n"
                    "    <transform name=\"toWorld\"><lookat origin=\"0, 5, 0\" target=\"0, 0, 0\" "
                    "up=\"0, 0, 1\"/></transform></emitter>\n</scene>\n");
  SceneDescription d = loadSceneDescription(path);
  ASSERT_EQ(d.pointLights.size(), 2u);
  expectNear(d.pointLights[0].position, Vec3f(1, 2, 3));
  expectNear(d.pointLights[0].intensity, Vec3f(4, 5, 6));
  const PointLightDescription& s = d.pointLights[1];
  EXPECT_TRUE(s.spot);
  expectNear(s.position, Vec3f(0, 5, 0));
  expectNear(s.direction, Vec3f(0, -1, 0));
  EXPECT_NEAR(s.cosTotalWidth, std::cos(30 * kPi / 180), 1e-6f);
  EXPECT_NEAR(s.cosFalloffStart, std::cos(22.5f * kPi / 180), 1e-6f);  // 3/4 of the cutoff
  EXPECT_EQ(s.falloff, PointLightDescription::Falloff::MitsubaLinearAngle);
}

TEST(AreaLightLoader, PbrtTwoSided) {
  TempDir dir;
  SceneDescription d = loadSceneDescription(
      dir.write("s.pbrt", pbrtScene("AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3] "
                                    "\"bool twosided\" true\nShape \"sphere\"\nAttributeEnd\n"
                                    "AreaLightSource \"diffuse\"\nShape \"sphere\"\n")));
  ASSERT_EQ(d.shapes.size(), 3u);  // the scene's own sphere first
  EXPECT_TRUE(d.shapes[1].isEmitter);
  EXPECT_TRUE(d.shapes[1].emitsBothSides);
  EXPECT_TRUE(d.shapes[2].isEmitter);
  EXPECT_FALSE(d.shapes[2].emitsBothSides);
}

TEST(EnvironmentLoader, BadEnvironmentsGetAClearError) {
  TempDir dir;
  writeMap(dir, "square.exr", 4, 4);
  writeMap(dir, "wide.exr", 12, 4);
  writeMap(dir, "sky.exr");
  struct Case {
    std::string name, text, message;
  };
  const std::string envmap = "<emitter type=\"envmap\"><string name=\"filename\" value=\"";
  const Case cases[] = {
      {"a.pbrt", pbrtScene("LightSource \"infinite\" \"string mapname\" \"square.exr\"\n"),
       "it must be a lat-long map, twice as wide as high"},
      {"b.pbrt", pbrtScene("LightSource \"infinite\" \"string filename\" \"wide.exr\"\n"),
       "it must be a square equal-area map (pbrt-v4) or a lat-long map"},
      {"c.pbrt", pbrtScene("LightSource \"infinite\"\nLightSource \"infinite\"\n"),
       "more than one infinite light"},
      {"d.pbrt", pbrtScene("Scale 1 2 1\nLightSource \"infinite\"\n"), "must be a rotation"},
      {"e.pbrt", pbrtScene("LightSource \"infinite\" \"string filename\" \"missing.exr\"\n"),
       "not found"},
      {"f.pbrt", pbrtScene("LightSource \"infinite\" \"string filename\" \"../sky.exr\"\n"),
       "outside"},
      {"g.pbrt",
       pbrtScene("LightSource \"infinite\" \"string filename\" \"sky.exr\" "
                 "\"string mapname\" \"sky.exr\"\n"),
       "both"},
      {"h.pbrt", pbrtScene("LightSource \"distant\"\n"), "light source 'distant' is not supported"},
      {"i.pbrt", pbrtScene("LightSource \"infinite\" \"rgb L\" [1 -1 1]\n"), "negative"},
      {"j.pbrt", pbrtScene("LightSource \"infinite\" \"float power\" 3\n"), "power"},
      {"k.xml",
       std::string(kMitsubaHead) + envmap + "sky.exr\"/></emitter>\n" + envmap +
           "sky.exr\"/></emitter>\n</scene>\n",
       "more than one environment emitter"},
      {"l.xml", std::string(kMitsubaHead) + "<emitter type=\"envmap\"/>\n</scene>\n",
       "envmap has no filename"},
      {"m.xml", std::string(kMitsubaHead) + "<emitter type=\"directional\"/>\n</scene>\n",
       "unsupported emitter type 'directional'"},
      {"n.xml",
       std::string(kMitsubaHead) + envmap +
           "sky.exr\"/><float name=\"gamma\" value=\"2.2\"/></emitter>\n</scene>\n",
       "unsupported parameter 'gamma'"},
      {"o.xml", std::string(kMitsubaHead) + envmap + "square.exr\"/></emitter>\n</scene>\n",
       "it must be a lat-long map"},
      {"p.pbrt", pbrtScene("LightSource \"spot\" \"float coneangle\" 0\n"), "coneangle"},
      {"q.pbrt", pbrtScene("LightSource \"spot\" \"point from\" [1 1 1] \"point to\" [1 1 1]\n"),
       "coincide"},
      {"r.pbrt", pbrtScene("LightSource \"point\" \"float power\" 10\n"), "'power'"},
      {"s.pbrt", pbrtScene("LightSource \"point\" \"rgb I\" [1 1]\n"), "3 numbers"},
      {"t.xml",
       std::string(kMitsubaHead) + "<emitter type=\"spot\"><float name=\"beamWidth\" value=\"40\"/>"
                                   "</emitter>\n</scene>\n",
       "beamWidth"},
      {"u.xml",
       std::string(kMitsubaHead) + "<emitter type=\"point\"><float name=\"radius\" value=\"1\"/>"
                                   "</emitter>\n</scene>\n",
       "unsupported parameter 'radius'"},
  };
  for (const Case& c : cases) {
    const std::string error = loadError(dir.write(c.name, c.text));
    EXPECT_NE(error.find(c.message), std::string::npos) << c.name << ": " << error;
  }
}

}  // namespace
}  // namespace farm
