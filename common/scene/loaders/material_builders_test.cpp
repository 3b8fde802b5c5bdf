#include "common/scene/loaders/material_builders.h"

#include <gtest/gtest.h>

#include <string>

#include "common/scene/loaders/temp_dir_for_tests.h"

namespace farm {
namespace {

// Every field a model reads; the coat's table by identity (identical coats share one).
void expectSameMaterial(const BsdfDescription& a, const BsdfDescription& b) {
  EXPECT_EQ(a.type, b.type);
  EXPECT_EQ(a.twoSided, b.twoSided);
  expectSameSpectrum(a.reflectance, b.reflectance, "reflectance");
  EXPECT_EQ(a.reflectanceTexture, b.reflectanceTexture);
  EXPECT_EQ(a.intIOR, b.intIOR);
  EXPECT_EQ(a.extIOR, b.extIOR);
  EXPECT_EQ(a.distribution, b.distribution);
  EXPECT_EQ(a.alpha, b.alpha);
  expectSameSpectrum(a.eta, b.eta, "eta");
  expectSameSpectrum(a.k, b.k, "k");
  EXPECT_EQ(a.extEta, b.extEta);
  expectSameSpectrum(a.specularReflectance, b.specularReflectance, "specularReflectance");
  EXPECT_EQ(a.coating, b.coating);
  EXPECT_EQ(a.nonlinear, b.nonlinear);
}

TEST(MaterialBuilders, AlphaZeroIsTheSmoothModelAndAboveItTheRoughOne) {
  EXPECT_EQ(conductorMaterial(Spectrum(0.2f), Spectrum(3.0f), 1.0f, Spectrum(1.0f), {}).type,
            BsdfDescription::Type::Conductor);
  const BsdfDescription rough = conductorMaterial(
      Spectrum(0.2f), Spectrum(3.0f), 1.33f, Spectrum(0.9f), {0.3f, MicrofacetDistribution::GGX});
  EXPECT_EQ(rough.type, BsdfDescription::Type::RoughConductor);
  EXPECT_EQ(rough.alpha, 0.3f);
  EXPECT_EQ(rough.distribution, MicrofacetDistribution::GGX);
  EXPECT_EQ(rough.extEta, 1.33f);
  expectSameSpectrum(rough.specularReflectance, Spectrum(0.9f), "the conductor's scale");
  EXPECT_EQ(dielectricMaterial(1.5f, 1.0f, {}).type, BsdfDescription::Type::Dielectric);
  const BsdfDescription glass =
      dielectricMaterial(1.33f, 1.1f, {0.05f, MicrofacetDistribution::Beckmann});
  EXPECT_EQ(glass.type, BsdfDescription::Type::RoughDielectric);
  EXPECT_EQ(glass.intIOR, 1.33f);
  EXPECT_EQ(glass.extIOR, 1.1f);
  EXPECT_EQ(glass.distribution, MicrofacetDistribution::Beckmann);
}

TEST(MaterialBuilders, ASmoothCoatIsATinyGgxCoatAndIdenticalCoatsShareTheirTable) {
  const BsdfDescription smooth =
      coatedDiffuseMaterial(Spectrum(0.5f), -1, Spectrum(1.0f), {}, 1.5f, 1.0f, false, "f", 1, "c");
  EXPECT_EQ(smooth.type, BsdfDescription::Type::CoatedDiffuse);
  EXPECT_EQ(smooth.alpha, kSmoothCoatAlpha);
  EXPECT_EQ(smooth.distribution, MicrofacetDistribution::GGX);
  ASSERT_TRUE(smooth.coating);
  const BsdfDescription again =
      coatedDiffuseMaterial(Spectrum(0.2f), 3, Spectrum(0.5f), {}, 1.5f, 1.0f, true, "g", 2, "d");
  EXPECT_EQ(again.coating, smooth.coating) << "the same coat, another base";
  EXPECT_EQ(again.reflectanceTexture, 3);
  const BsdfDescription rough = coatedDiffuseMaterial(Spectrum(0.5f), -1, Spectrum(1.0f),
                                                      {0.2f, MicrofacetDistribution::Beckmann},
                                                      1.5f, 1.0f, false, "f", 1, "c");
  EXPECT_EQ(rough.distribution, MicrofacetDistribution::Beckmann);
  EXPECT_NE(rough.coating, smooth.coating);
}

TEST(MaterialBuilders, ACoatThatCreatesEnergyOrDoesNotRefractIsRefusedWhereItIsDefined) {
  const SceneLoadError bright = thrownLoadError(
      [] {
        coatedDiffuseMaterial(Spectrum(0.5f, 1.2f, 0.5f), -1, Spectrum(1.0f), {}, 1.5f, 1.0f, false,
                              "room.xml", 7, "bsdf type 'plastic'");
      },
      "accepted a base reflecting more than it receives");
  EXPECT_EQ(bright.file(), "room.xml");
  EXPECT_EQ(bright.line(), 7);
  EXPECT_EQ(bright.problem(), "bsdf type 'plastic': a reflectance above 1 would create energy");
  const SceneLoadError flat = thrownLoadError(
      [] {
        coatedDiffuseMaterial(Spectrum(0.5f), -1, Spectrum(1.0f), {}, 1.3f, 1.3f, false,
                              "room.pbrt", 9, "material 'coateddiffuse'");
      },
      "accepted a coat of the outside's index");
  EXPECT_EQ(flat.line(), 9);
  EXPECT_NE(flat.problem().find("intIOR and extIOR must differ"), std::string::npos);
}

TEST(MaterialBuilders, PbrtsNamedMetalsAreFoundByName) {
  ASSERT_NE(pbrtNamedMetal("Au"), nullptr);
  EXPECT_FLOAT_EQ(pbrtNamedMetal("Au")->eta.z, 1.4424785571f);
  EXPECT_EQ(pbrtNamedMetal("Unobtainium"), nullptr);
  EXPECT_EQ(pbrtNamedMetals().size(), 7u);
  // pbrt's and Mitsuba's copper are two fits of one metal: close, not equal.
  EXPECT_NEAR(pbrtNamedMetal("Cu")->eta.y, mitsubaCopper().eta.y, 1e-5f);
}

// The table in material_builders.h read off the loaders: each row's names in each format make the
// same description (pbrt's surfaces scatter on both sides, as a Mitsuba one wrapped in twosided
// does; pbrt-v4's roughness is alpha squared).
TEST(MaterialBuilders, TheSameMaterialInEitherFormatIsTheSameDescription) {
  TempDir dir("materials_test");
  const std::string xml = dir.write(
      "m.xml",
      "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n"
      "<bsdf type=\"twosided\" id=\"a\"><bsdf type=\"diffuse\">"
      "<rgb name=\"reflectance\" value=\"0.2 0.4 0.6\"/></bsdf></bsdf>\n"
      "<bsdf type=\"twosided\" id=\"b\"><bsdf type=\"roughconductor\">"
      "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.25\"/>"
      "<rgb name=\"eta\" value=\"0.2 0.9 1.1\"/><rgb name=\"k\" value=\"3.9 2.4 2.1\"/>"
      "</bsdf></bsdf>\n"
      "<bsdf type=\"dielectric\" id=\"c\"><float name=\"intIOR\" value=\"1.33\"/>"
      "<float name=\"extIOR\" value=\"1\"/></bsdf>\n"
      "<bsdf type=\"twosided\" id=\"d\"><bsdf type=\"roughplastic\">"
      "<string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"0.25\"/>"
      "<float name=\"intIOR\" value=\"1.5\"/><float name=\"extIOR\" value=\"1\"/>"
      "<boolean name=\"nonlinear\" value=\"true\"/>"
      "<rgb name=\"diffuseReflectance\" value=\"0.3 0.5 0.7\"/></bsdf></bsdf>\n"
      "</scene>\n");
  const std::string pbrt = dir.write(
      "m.pbrt",
      "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [ 45 ]\nWorldBegin\n"
      "MakeNamedMaterial \"a\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.2 0.4 0.6]\n"
      "MakeNamedMaterial \"b\" \"string type\" \"conductor\" \"float roughness\" [0.0625] "
      "\"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1]\n"
      "MakeNamedMaterial \"c\" \"string type\" \"dielectric\" \"float eta\" [1.33]\n"
      "MakeNamedMaterial \"d\" \"string type\" \"coateddiffuse\" \"float roughness\" [0.0625] "
      "\"rgb reflectance\" [0.3 0.5 0.7]\n"
      "NamedMaterial \"a\"\nShape \"sphere\" \"float radius\" [1]\n");
  const SceneDescription m = loadSceneDescription(xml);
  const SceneDescription p = loadSceneDescription(pbrt);
  ASSERT_EQ(m.bsdfs.size(), 4u);
  ASSERT_EQ(p.bsdfs.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE("material " + m.bsdfs[i].id);
    expectSameMaterial(m.bsdfs[i], p.bsdfs[i]);
  }
}

}  // namespace
}  // namespace farm
