// The plan of each shared scene and of the test scenes with a lens, an environment and media:
// what the analysis finds, the candidates auto's pilot may rank, and each part in or left out
// with its reason.
#include "common/plan/render_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/render/render_job.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/loaders/temp_dir_for_tests.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;
const std::string kTestData = FARM_TEST_DATA_DIR;

RenderPlan plan(const std::string& path, Algorithm algorithm, bool automatic) {
  RenderSettings settings;
  settings.autoAlgorithm = true;  // load whatever the scene has
  std::shared_ptr<Scene> scene = loadScene(path, settings);
  return planRender(analyseScene(*scene), algorithm, automatic, MutationMix());
}

const PlanPart& part(const RenderPlan& p, const std::string& name) {
  for (const PlanPart& part : p.parts)
    if (part.name == name) return part;
  ADD_FAILURE() << "no part " << name;
  static const PlanPart none;
  return none;
}

bool candidate(const RenderPlan& p, Algorithm a) {
  return std::find(p.shortlist.begin(), p.shortlist.end(), a) != p.shortlist.end();
}

// Every line of the plan that leaves a part out names it and says why.
void expectNamedLeftOuts(const RenderPlan& p, const std::string& scene) {
  size_t leftOut = 0;
  for (const std::string& line : p.describe()) {
    if (line.find("left out: ") == std::string::npos) continue;
    ++leftOut;
    EXPECT_NE(line.find(" ("), std::string::npos) << scene << ": no reason in '" << line << "'";
  }
  size_t parts = 0;
  for (const PlanPart& part : p.parts) parts += !part.enabled;
  EXPECT_EQ(leftOut, parts) << scene;
  EXPECT_GT(leftOut, 0u) << scene << ": every shared scene lacks something";
}

// The plan names the shading-normal convention and the smooth-shaded shapes it applies to (those
// whose vertex normals part from their faces'): the water's surface, under the file's strict
// normals unless the settings say lax.
TEST(RenderPlan, NamesTheShadingNormalConvention) {
  const std::string water = kShared + "/scenes/water-caustic/scene.xml";
  auto line = [](const RenderPlan& p) {
    for (const std::string& l : p.describe())
      if (l.rfind("shading normals: ", 0) == 0) return l;
    return std::string();
  };
  const RenderPlan strict = plan(water, Algorithm::MLT, false);
  EXPECT_TRUE(strict.scene.strictNormals);
  EXPECT_GE(strict.scene.smoothShapes, 1);
  EXPECT_EQ(line(strict).rfind("shading normals: strict, ", 0), 0u) << line(strict);
  EXPECT_NE(line(strict).find("--shading-normals lax keeps them"), std::string::npos);
  RenderSettings settings;
  settings.algorithm = Algorithm::MLT;
  settings.shadingNormals = ShadingNormals::Lax;
  const RenderPlan lax =
      planRender(analyseScene(*loadScene(water, settings)), Algorithm::MLT, false, MutationMix());
  EXPECT_FALSE(lax.scene.strictNormals);
  EXPECT_EQ(line(lax), "shading normals: lax, " + std::to_string(strict.scene.smoothShapes) +
                           " smooth-shaded shape(s)");
  // The Cornell box's OBJ walls carry vertex normals, their faces' own: nothing to disagree on.
  const RenderPlan cornell = plan(kShared + "/scenes/cornell-box/scene.xml", Algorithm::MLT, false);
  EXPECT_EQ(cornell.scene.smoothShapes, 0);
  EXPECT_EQ(line(cornell), "shading normals: strict, 0 smooth-shaded shape(s)");
}

TEST(RenderPlan, CornellBoxIsDiffuseUnderOneLargeLight) {
  const std::string path = kShared + "/scenes/cornell-box/scene.xml";
  const RenderPlan p = plan(path, Algorithm::MLT, false);
  EXPECT_EQ(p.scene.specularShapes, 0);
  EXPECT_EQ(p.scene.diffuseShapes, 8);
  ASSERT_EQ(p.scene.lights.size(), 1u);
  EXPECT_FALSE(p.scene.smallLights);
  EXPECT_FALSE(p.scene.specularDiffuseSpecular());
  // Two thirds of what the camera sees sees the light: the light is not hidden.
  EXPECT_GT(p.scene.directlyLit, 0.6);
  EXPECT_LT(p.scene.directlyLit, 0.75);
  // mlt's mutations for specular chains are left out, and at zero weight; the caustic
  // perturbation stays (it moves D D E paths too).
  EXPECT_FALSE(part(p, "multi-chain perturbation").enabled);
  EXPECT_NE(part(p, "multi-chain perturbation").reason.find("no specular surfaces"),
            std::string::npos);
  EXPECT_FALSE(part(p, "manifold perturbation").enabled);
  EXPECT_EQ(p.mutationMix.multiChainPerturbation, 0);
  EXPECT_EQ(p.mutationMix.manifoldPerturbation, 0);
  EXPECT_TRUE(part(p, "caustic perturbation").enabled);
  EXPECT_EQ(p.mutationMix.causticPerturbation, MutationMix().causticPerturbation);
  EXPECT_FALSE(part(p, "manifold next-event estimation").enabled);
  EXPECT_FALSE(part(p, "lens sampling").enabled);
  EXPECT_FALSE(part(p, "texture lookups").enabled);
  EXPECT_FALSE(part(p, "escaped-path handling").enabled);
  EXPECT_FALSE(part(p, "medium tracking").enabled);
  EXPECT_TRUE(part(p, "seen emission apart").enabled);
  EXPECT_FALSE(part(plan(path, Algorithm::PSSMLT, false), "seen emission apart").enabled);
  expectNamedLeftOuts(p, path);

  const RenderPlan automatic = plan(path, Algorithm::PSSMLT, true);
  ASSERT_FALSE(automatic.shortlist.empty());
  EXPECT_EQ(automatic.shortlist.front(), Algorithm::PathTracing) << "no small light";
  EXPECT_TRUE(candidate(automatic, Algorithm::Bidirectional));
  EXPECT_FALSE(candidate(automatic, Algorithm::MLT)) << "nothing specular to follow";
}

TEST(RenderPlan, WaterCausticIsSpecularDiffuseSpecularAndOnlyMltMayRenderIt) {
  const std::string path = kShared + "/scenes/water-caustic/scene.xml";
  const RenderPlan p = plan(path, Algorithm::PSSMLT, true);
  EXPECT_EQ(p.scene.specularShapes, 2);
  EXPECT_TRUE(p.scene.smallLights);
  EXPECT_GT(p.scene.specularSeen, 0.5);
  EXPECT_GT(p.scene.specularLit, 0.5);
  EXPECT_TRUE(p.scene.specularDiffuseSpecular());
  ASSERT_EQ(p.shortlist.size(), 1u);
  EXPECT_EQ(p.shortlist[0], Algorithm::MLT);
  EXPECT_EQ(p.algorithm, Algorithm::MLT);
  EXPECT_TRUE(part(p, "manifold perturbation").enabled);
  EXPECT_TRUE(part(p, "multi-chain perturbation").enabled);
  EXPECT_TRUE(part(p, "manifold next-event estimation").enabled);
  EXPECT_TRUE(part(p, "seen emission apart").enabled);
  EXPECT_EQ(p.mutationMix, MutationMix());
  EXPECT_EQ(p.scene.facetedSpecularShapes, 0);
  expectNamedLeftOuts(p, path);

  // With face normals its waves are faceted: manifold next-event estimation keeps to the flat
  // front face and says that BDPT keeps the waves' paths (ManifoldNextEvent::covers).
  SceneDescription d = loadSceneDescription(path);
  for (ShapeDescription& shape : d.shapes) shape.faceNormals = true;
  const RenderPlan faceted =
      planRender(analyseScene(Scene(d)), Algorithm::PSSMLT, true, MutationMix());
  EXPECT_EQ(faceted.scene.facetedSpecularShapes, 1);
  const PlanPart& nee = part(faceted, "manifold next-event estimation");
  EXPECT_TRUE(nee.enabled);
  EXPECT_NE(nee.reason.find("faceted specular shapes (1 here"), std::string::npos) << nee.reason;
  // Every specular shape faceted: none is left to it.
  SceneDescription onlyWaves = d;
  for (ShapeDescription& shape : onlyWaves.shapes) {
    if (shape.normals.empty() && shape.bsdf >= 0 &&
        onlyWaves.bsdfs[size_t(shape.bsdf)].type == BsdfDescription::Type::Dielectric)
      shape.bsdf = 0;  // the flat front face made diffuse
  }
  const RenderPlan wavesOnly =
      planRender(analyseScene(Scene(onlyWaves)), Algorithm::PSSMLT, true, MutationMix());
  const PlanPart& none = part(wavesOnly, "manifold next-event estimation");
  EXPECT_FALSE(none.enabled);
  EXPECT_NE(none.reason.find("every specular shape is faceted"), std::string::npos) << none.reason;
}

// A little of its light comes through the glass egg from the small lamp and is seen through
// it: too little for mlt alone, enough for pt's and bdpt's fireflies.
TEST(RenderPlan, VeachBidirHasALittleSpecularDiffuseSpecularLight) {
  const std::string path = kShared + "/scenes/veach-bidir/scene.xml";
  const RenderPlan p = plan(path, Algorithm::PSSMLT, true);
  EXPECT_GT(p.scene.specularShapes, 0);
  EXPECT_GT(p.scene.glossyShapes, 0);
  EXPECT_EQ(p.scene.lights.size(), 2u);
  EXPECT_GT(p.scene.specularSeen, 0);
  EXPECT_GT(p.scene.specularLit, 0);
  EXPECT_FALSE(p.scene.specularDiffuseSpecular());
  // Its lamp is beside the egg, not in it: no light inside glass for bdpt to carry out.
  EXPECT_LT(p.scene.specularLit, kLightsInGlass);
  ASSERT_FALSE(p.shortlist.empty());
  EXPECT_EQ(p.shortlist.front(), Algorithm::MMLT);
  EXPECT_TRUE(candidate(p, Algorithm::MLT));
  EXPECT_TRUE(candidate(p, Algorithm::PSSMLT));
  EXPECT_FALSE(candidate(p, Algorithm::Bidirectional)) << "fireflies a pilot does not see";
  EXPECT_FALSE(candidate(p, Algorithm::PathTracing));
  EXPECT_FALSE(candidate(p, Algorithm::ERPT));
  expectNamedLeftOuts(p, path);
}

TEST(RenderPlan, VeachMisAndAjar) {
  const std::string mis = kShared + "/scenes/veach-mis/scene.xml";
  const RenderPlan m = plan(mis, Algorithm::MLT, false);
  EXPECT_EQ(m.scene.specularShapes, 0);
  EXPECT_EQ(m.scene.glossyShapes, 4);
  EXPECT_EQ(m.scene.lights.size(), 3u);
  EXPECT_FALSE(part(m, "manifold perturbation").enabled);
  expectNamedLeftOuts(m, mis);
  const RenderPlan mAuto = plan(mis, Algorithm::PSSMLT, true);
  ASSERT_FALSE(mAuto.shortlist.empty());
  EXPECT_EQ(mAuto.shortlist.front(), Algorithm::PathTracing)
      << "small lights, but in sight (bdpt first under them left 1.6x pt's error on the corpus)";

  const std::string ajar = kShared + "/scenes/veach-ajar/scene.pbrt";
  const RenderPlan a = plan(ajar, Algorithm::Bidirectional, false);
  EXPECT_GT(a.scene.texturedBsdfs, 0);
  EXPECT_TRUE(part(a, "texture lookups").enabled);
  EXPECT_FALSE(part(a, "lens sampling").enabled);
  expectNamedLeftOuts(a, ajar);
  const RenderPlan aAuto = plan(ajar, Algorithm::PSSMLT, true);
  ASSERT_FALSE(aAuto.shortlist.empty());
  EXPECT_EQ(aAuto.shortlist.front(), Algorithm::MLT) << "specular, but no such light";
  EXPECT_FALSE(aAuto.scene.specularDiffuseSpecular());
  // The light is behind the door ajar: next to nothing the camera sees sees it.
  EXPECT_LT(a.scene.directlyLit, 0.02);
  EXPECT_GT(m.scene.directlyLit, kFewDirectlyLit);
}

// A camera looks along +z through a slab of fog (z in [1, 3], extinction sigma, no absorption)
// at a glass ball (z = 4, radius 0.2) before a wall (z = 5), a small light above the ball.
std::string fogSlab(double sigma) {
  char medium[256];
  std::snprintf(medium, sizeof(medium),
                "<medium type=\"homogeneous\" id=\"fog\"><rgb name=\"sigmaA\" value=\"0, 0, "
                "0\"/><rgb name=\"sigmaS\" value=\"%g, %g, %g\"/></medium>",
                sigma, sigma, sigma);
  return std::string(R"(<?xml version="1.0"?>
<scene version="0.5.0">
  <sensor type="perspective"><float name="fov" value="10"/>
    <transform name="toWorld"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film>
  </sensor>
  )") + medium +
         R"(
  <shape type="rectangle"><transform name="toWorld"><scale x="10" y="10"/><rotate y="1" angle="180"/><translate x="0" y="0" z="5"/></transform><bsdf type="diffuse"/></shape>
  <shape type="cube"><transform name="toWorld"><scale x="10" y="10" z="1"/><translate x="0" y="0" z="2"/></transform><ref name="interior" id="fog"/></shape>
  <shape type="sphere"><point name="center" x="0" y="0" z="4"/><float name="radius" value="0.2"/><bsdf type="dielectric"><float name="intIOR" value="1.5"/></bsdf></shape>
  <shape type="rectangle"><transform name="toWorld"><scale x="0.05" y="0.05"/><rotate x="1" angle="90"/><translate x="0" y="0.6" z="4"/></transform><emitter type="area"><rgb name="radiance" value="100, 100, 100"/></emitter></shape>
</scene>
)";
}

// The probes look through the faces of a box that only holds a medium (issue 43): they see the
// glass behind it, and measure what the fog takes from the camera's rays against the closed
// form 1 - exp(-sigma d / cos theta), d = 2 the slab's thickness, theta from 0 on the axis to
// the film's corner. The ball, seen and lit, under a small light: in vacuum only mlt's
// manifold walks connect its light; with the fog the plan leaves those rules, fitted in vacuum,
// to the candidates of a scene without such light; with the fog nearly empty they hold.
TEST(RenderPlan, TheProbesSeeGlassThroughAFogsBoundary) {
  TempDir dir("render_plan_test");
  const std::string fogFile = dir.write("fog/scene.xml", fogSlab(0.5));
  const RenderPlan fog = plan(fogFile, Algorithm::PSSMLT, true);
  EXPECT_EQ(fog.scene.homogeneousMedia, 1);
  // The ball's disc covers pi tan^2(asin(0.2 / 4)) of the film's (2 tan 5 deg)^2.
  const double half = std::tan(5.0 * M_PI / 180);
  const double disc = M_PI * std::pow(std::tan(std::asin(0.05)), 2) / (4 * half * half);
  EXPECT_NEAR(fog.scene.specularSeen, disc, 0.02) << "the ball, seen through the fog's box";
  EXPECT_GT(fog.scene.specularLit, 0.02) << "the light above the ball lights it";
  const double cosCorner = 1 / std::sqrt(1 + 2 * half * half);
  EXPECT_GT(fog.scene.mediaSeen, 1 - std::exp(-1.0) - 1e-4);
  EXPECT_LT(fog.scene.mediaSeen, 1 - std::exp(-1.0 / cosCorner) + 1e-4);
  ASSERT_EQ(fog.scene.mediaLookedThrough.size(), 1u);
  EXPECT_EQ(fog.scene.mediaLookedThrough[0].first, "fog");
  EXPECT_EQ(fog.scene.mediaLookedThrough[0].second, 1.0) << "every camera ray crosses the slab";
  EXPECT_TRUE(fog.scene.specularDiffuseSpecular());
  ASSERT_FALSE(fog.shortlist.empty());
  EXPECT_EQ(fog.shortlist.front(), Algorithm::Bidirectional);
  EXPECT_FALSE(candidate(fog, Algorithm::MLT));
  EXPECT_FALSE(candidate(fog, Algorithm::MMLT));
  EXPECT_NE(fog.why.find("seen through fog"), std::string::npos) << fog.why;
  EXPECT_EQ(plan(fogFile, Algorithm::MMLT, false).chains, 0)
      << "the chains' count for specular-diffuse-specular light was fitted in vacuum";

  const std::string clearFile = dir.write("clear/scene.xml", fogSlab(1e-6));
  const RenderPlan clear = plan(clearFile, Algorithm::PSSMLT, true);
  EXPECT_LT(clear.scene.mediaSeen, 1e-5);
  EXPECT_NEAR(clear.scene.specularSeen, fog.scene.specularSeen, 1e-9);
  ASSERT_FALSE(clear.shortlist.empty());
  EXPECT_EQ(clear.shortlist, std::vector<Algorithm>{Algorithm::MLT}) << clear.why;
  EXPECT_EQ(plan(clearFile, Algorithm::MMLT, false).chains, kSdsChains);
}

TEST(RenderPlan, ALensAnEnvironmentAndMediaAreInAndNarrowTheCandidates) {
  const RenderPlan lens = plan(kTestData + "/thin-lens/scene.pbrt", Algorithm::PSSMLT, true);
  EXPECT_TRUE(lens.scene.thinLens);
  EXPECT_TRUE(part(lens, "lens sampling").enabled);
  // Every algorithm takes a lens (path-space MLT's mutations regrow the lens point): mlt is
  // left out only because the lights are in sight, not refused.
  for (const std::string& n : lens.notShortlisted) {
    EXPECT_EQ(n.find("thin lens"), std::string::npos) << n;
    if (n.rfind("mlt: ", 0) == 0) {
      EXPECT_NE(n.find("lights in sight"), std::string::npos) << n;
    }
  }
  SceneDescription lensDesc;
  lensDesc.camera.lensRadius = 0.4f;
  for (Algorithm a : {Algorithm::MLT, Algorithm::ERPT})
    EXPECT_EQ(algorithmRefusal(lensDesc, a), "") << algorithmName(a);

  const RenderPlan sky = plan(kTestData + "/sky/scene.pbrt", Algorithm::PSSMLT, true);
  EXPECT_TRUE(sky.scene.environment);
  EXPECT_TRUE(part(sky, "escaped-path handling").enabled);
  EXPECT_FALSE(candidate(sky, Algorithm::MLT));

  const RenderPlan smoke = plan(kTestData + "/smoke-room/scene.xml", Algorithm::PSSMLT, true);
  EXPECT_GT(smoke.scene.gridMedia, 0);
  EXPECT_TRUE(part(smoke, "medium tracking").enabled);
  EXPECT_FALSE(
      part(plan(kTestData + "/smoke-room/scene.xml", Algorithm::MLT, false), "seen emission apart")
          .enabled)
      << "through media the chains keep the lights they see";
  EXPECT_FALSE(candidate(smoke, Algorithm::ERPT));
}

}  // namespace
}  // namespace farm
