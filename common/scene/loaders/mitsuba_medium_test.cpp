// Mitsuba 0.6's participating media: homogeneous and heterogeneous <medium>s, their phase
// functions, where shapes and the sensor refer to them, the gridvolume file format, and a
// clear error for each form that is not supported or not well formed.
#include <gtest/gtest.h>

#include <string>

#include "common/scene/loaders/grid_volume_reader.h"
#include "common/scene/loaders/mitsuba_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

std::string sceneXml(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n" + body + "</scene>\n";
}

void expectSpectrum(const Spectrum& s, float r, float g, float b) {
  EXPECT_NEAR(s.x, r, 1e-6f);
  EXPECT_NEAR(s.y, g, 1e-6f);
  EXPECT_NEAR(s.z, b, 1e-6f);
}

TEST(MitsubaMedia, HomogeneousMediaAndTheirReferences) {
  TempDir dir;
  const SceneDescription s = loadMitsubaScene(dir.write("m.xml", sceneXml(R"(
<medium type="homogeneous" id="fog">
  <rgb name="sigmaA" value="0.1, 0.2, 0.3"/>
  <rgb name="sigmaS" value="1, 2, 3"/>
  <float name="scale" value="2"/>
  <phase type="hg"><float name="g" value="0.7"/></phase>
</medium>
<sensor type="perspective"><ref id="fog"/></sensor>
<shape type="cube"><ref name="interior" id="fog"/></shape>
<shape type="sphere">
  <bsdf type="dielectric"/>
  <medium name="interior" type="homogeneous">
    <rgb name="sigmaT" value="2, 4, 8"/>
    <rgb name="albedo" value="0.5, 0.25, 1"/>
  </medium>
  <ref name="exterior" id="fog"/>
</shape>
<shape type="rectangle"/>
)")));
  ASSERT_EQ(s.media.size(), 2u);
  expectSpectrum(s.media[0].sigmaA, 0.2f, 0.4f, 0.6f);
  expectSpectrum(s.media[0].sigmaS, 2, 4, 6);
  EXPECT_FLOAT_EQ(s.media[0].g, 0.7f);
  EXPECT_EQ(s.media[0].type, MediumDescription::Type::Homogeneous);
  expectSpectrum(s.media[1].sigmaS, 1, 1, 8);
  expectSpectrum(s.media[1].sigmaA, 1, 3, 0);
  EXPECT_FLOAT_EQ(s.media[1].g, 0);
  EXPECT_EQ(s.camera.medium, 0);
  ASSERT_EQ(s.shapes.size(), 3u);
  // The cube has a medium and no BSDF: it only bounds the fog.
  EXPECT_TRUE(s.shapes[0].nullBoundary);
  EXPECT_TRUE(s.shapes[0].hasMediumInterface);
  EXPECT_EQ(s.shapes[0].interiorMedium, 0);
  EXPECT_EQ(s.shapes[0].exteriorMedium, -1);
  // The sphere is glass with its own medium inside and the fog outside.
  EXPECT_FALSE(s.shapes[1].nullBoundary);
  EXPECT_EQ(s.shapes[1].interiorMedium, 1);
  EXPECT_EQ(s.shapes[1].exteriorMedium, 0);
  // A plain shape keeps whatever medium a ray is in, and scatters.
  EXPECT_FALSE(s.shapes[2].hasMediumInterface);
  EXPECT_FALSE(s.shapes[2].nullBoundary);
  EXPECT_GE(s.shapes[2].bsdf, 0);
}

TEST(MitsubaMedia, HeterogeneousMediumReadsItsGridVolume) {
  TempDir dir;
  GridVolume v;
  v.nx = 3, v.ny = 2, v.nz = 2;
  v.boundsMin = Vec3f(-1, 0, 0);
  v.boundsMax = Vec3f(1, 1, 4);
  for (int i = 0; i < 12; ++i) v.values.push_back(0.25f * float(i));
  dir.write("smoke.vol", encodeGridVolume(v));
  const SceneDescription s = loadMitsubaScene(dir.write("h.xml", sceneXml(R"(
<medium type="heterogeneous" id="smoke">
  <volume name="density" type="gridvolume">
    <string name="filename" value="smoke.vol"/>
    <transform name="toWorld"><translate x="10"/></transform>
  </volume>
  <volume name="albedo" type="constvolume"><rgb name="value" value="0.9, 0.5, 0.1"/></volume>
  <float name="scale" value="3"/>
  <phase type="isotropic"/>
</medium>
<shape type="cube"><ref name="interior" id="smoke"/></shape>
)")));
  ASSERT_EQ(s.media.size(), 1u);
  const MediumDescription& m = s.media[0];
  EXPECT_EQ(m.type, MediumDescription::Type::Grid);
  EXPECT_EQ(m.nx, 3);
  EXPECT_EQ(m.ny, 2);
  EXPECT_EQ(m.nz, 2);
  EXPECT_EQ(m.density, v.values);
  EXPECT_FALSE(m.cellCentred);
  expectSpectrum(m.sigmaS, 2.7f, 1.5f, 0.3f);
  expectSpectrum(m.sigmaA + m.sigmaS, 3, 3, 3);
  // The volume's box, moved by its toWorld, maps onto the unit cube.
  const Vec3f lo = m.worldToGrid.applyPoint(Vec3f(9, 0, 0));
  const Vec3f hi = m.worldToGrid.applyPoint(Vec3f(11, 1, 4));
  EXPECT_NEAR(length(lo), 0, 1e-5f);
  EXPECT_NEAR(length(hi - Vec3f(1.0f)), 0, 1e-5f);
}

TEST(MitsubaMedia, UnsupportedAndMalformedMediaAreClearErrors) {
  TempDir dir;
  GridVolume v;
  v.nx = v.ny = v.nz = 2;
  v.boundsMin = Vec3f(0.0f);
  v.boundsMax = Vec3f(1.0f);
  v.values.assign(8, 1.0f);
  std::string bytes = encodeGridVolume(v);
  dir.write("cut.vol", bytes.substr(0, bytes.size() - 3));
  dir.write("ok.vol", bytes);
  std::string badVersion = bytes;
  badVersion[3] = 2;
  dir.write("v2.vol", badVersion);
  dir.write("text.vol", "hello, world, this is not a volume file at all.....");

  struct Case {
    const char* body;
    const char* message;
    int line;
  };
  const Case cases[] = {
      {"<medium type=\"fog\"/>\n", "unknown or unsupported medium type 'fog'", 3},
      {"<medium type=\"homogeneous\">\n<string name=\"material\" value=\"Ketchup\"/></medium>\n",
       "named medium materials", 4},
      {"<medium type=\"homogeneous\"><float name=\"sigmaA\" value=\"1\"/>\n<float "
       "name=\"sigmaT\" value=\"1\"/></medium>\n",
       "not both", 3},
      {"<medium type=\"homogeneous\">\n<phase type=\"rayleigh\"/></medium>\n",
       "unsupported phase function 'rayleigh'", 4},
      {"<medium type=\"homogeneous\">\n<phase type=\"hg\"><float name=\"g\" value=\"1\"/>"
       "</phase></medium>\n",
       "(-1, 1)", 4},
      {"<medium type=\"homogeneous\">\n<float name=\"sigmaS\" value=\"-2\"/></medium>\n",
       "must not be negative", 4},
      {"<medium type=\"homogeneous\">\n<float name=\"density\" value=\"2\"/></medium>\n",
       "unsupported parameter 'density'", 4},
      {"<medium type=\"heterogeneous\"/>\n", "needs a <volume name=\"density\">", 3},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\">\n<string "
       "name=\"filename\" value=\"cut.vol\"/></volume></medium>\n",
       "cut.vol: the grid volume has", 4},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\">\n<string "
       "name=\"filename\" value=\"v2.vol\"/></volume></medium>\n",
       "version 2", 4},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\">\n<string "
       "name=\"filename\" value=\"text.vol\"/></volume></medium>\n",
       "does not start with \"VOL\"", 4},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\">\n<string "
       "name=\"filename\" value=\"../ok.vol\"/></volume></medium>\n",
       "volume file", 4},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\">\n<string "
       "name=\"filename\" value=\"missing.vol\"/></volume></medium>\n",
       "missing.vol", 4},
      {"<medium type=\"heterogeneous\"><volume name=\"density\" type=\"gridvolume\"><string "
       "name=\"filename\" value=\"ok.vol\"/></volume>\n<volume name=\"albedo\" "
       "type=\"gridvolume\"/></medium>\n",
       "must be a constvolume", 4},
      {"<bsdf type=\"diffuse\" id=\"white\"/>\n<shape type=\"cube\">\n<ref name=\"interior\" "
       "id=\"white\"/></shape>\n",
       "names a <bsdf>", 5},
      {"<medium type=\"homogeneous\" id=\"m\"/>\n<shape type=\"cube\">\n<ref name=\"interior\" "
       "id=\"m\"/><emitter type=\"area\"/></shape>\n",
       "needs a BSDF", 4},
      {"<medium type=\"homogeneous\" id=\"m\"/>\n<shape type=\"cube\"><ref name=\"interior\" "
       "id=\"m\"/>\n<ref name=\"interior\" id=\"m\"/></shape>\n",
       "more than one interior medium", 5},
  };
  int k = 0;
  for (const Case& c : cases) {
    const std::string path = dir.write("bad" + std::to_string(k++) + ".xml", sceneXml(c.body));
    expectLoadError(path, c.message, c.line);
  }
}

}  // namespace
}  // namespace farm
