#include "common/scene/loaders/medium_builders.h"

#include <gtest/gtest.h>

#include <string>

#include "common/scene/loaders/scene_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

TEST(MediumBuilders, AnExtinctionAndAnAlbedoSplitIntoAbsorptionAndScattering) {
  MediumDescription m;
  setExtinction(&m, Spectrum(2, 4, 8), Spectrum(0.5f, 0.25f, 1), 3);
  expectSameSpectrum(m.sigmaS, Spectrum(3, 3, 24), "sigma_s = albedo sigma_t, times the scale");
  expectSameSpectrum(m.sigmaA, Spectrum(3, 9, 0), "sigma_a = sigma_t - sigma_s, times the scale");
  setScattering(&m, Spectrum(0.5f, 1, 0), Spectrum(1, 2, 4), 0.5);
  expectSameSpectrum(m.sigmaA, Spectrum(0.25f, 0.5f, 0), "sigma_a");
  expectSameSpectrum(m.sigmaS, Spectrum(0.5f, 1, 2), "sigma_s");
}

// The table in medium_builders.h read off the loaders: one fog in pbrt's words and in both of
// Mitsuba's (its coefficients, and its extinction and albedo) is one description.
TEST(MediumBuilders, TheSameFogInEitherFormatIsTheSameMedium) {
  TempDir dir("medium_builders_test");
  const SceneDescription m = loadSceneDescription(
      dir.write("m.xml",
                "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n"
                "<medium type=\"homogeneous\" id=\"a\"><rgb name=\"sigmaA\" value=\"0.5 0.25 0\"/>"
                "<rgb name=\"sigmaS\" value=\"1.5 0.75 2\"/><float name=\"scale\" value=\"2\"/>"
                "<phase type=\"hg\"><float name=\"g\" value=\"0.25\"/></phase></medium>\n"
                "<medium type=\"homogeneous\" id=\"b\"><rgb name=\"sigmaT\" value=\"2 1 2\"/>"
                "<rgb name=\"albedo\" value=\"0.75 0.75 1\"/><float name=\"scale\" value=\"2\"/>"
                "<phase type=\"hg\"><float name=\"g\" value=\"0.25\"/></phase></medium>\n"
                "</scene>\n"));
  const SceneDescription p = loadSceneDescription(dir.write(
      "m.pbrt",
      "MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.5 0.25 0] "
      "\"rgb sigma_s\" [1.5 0.75 2] \"float scale\" [2] \"float g\" [0.25]\n"
      "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [ 45 ]\nWorldBegin\n"
      "Shape \"sphere\" \"float radius\" [1]\n"));
  ASSERT_EQ(m.media.size(), 2u);
  ASSERT_EQ(p.media.size(), 1u);
  for (const MediumDescription& mitsuba : m.media) {
    SCOPED_TRACE("Mitsuba's medium " + mitsuba.id);
    expectSameSpectrum(mitsuba.sigmaA, p.media[0].sigmaA, "sigma_a");
    expectSameSpectrum(mitsuba.sigmaS, p.media[0].sigmaS, "sigma_s");
    EXPECT_EQ(mitsuba.g, p.media[0].g);
    EXPECT_EQ(mitsuba.type, p.media[0].type);
  }
}

}  // namespace
}  // namespace farm
