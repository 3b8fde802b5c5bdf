// The path-space representation agrees with the estimator it comes from: for every strategy
// (s, t) of many BDPT samples, f(x) of the path it built divided by the strategy's density
// prod_{i<s} pL[i] prod_{i>=s} pE[i] (both from the vertices alone) is the unweighted value BDPT
// computed along the way, colour and film point included, on the shared scenes (diffuse, glossy
// conductors, glass and water). Paths of at most five vertices: BDPT's Russian roulette starts
// later, so the densities are exactly its sampling densities. And a path survives its byte form.
//
// BDPT starts each ray a small distance off the surface (Scene::spawnRay), so the edge between two
// of its vertices points up to about 1e-4 radians away from the direction it sampled. Diffuse and
// specular vertices do not notice (a Dirac lobe is told by the sides of its two directions); a
// glossy lobe of roughness 0.01 changes by several per cent over that angle, and so does a rough
// dielectric near grazing or near its critical angle (illConditioned), and so does the cosine of
// a grazing or a very short edge (edgeIllConditioned). So paths through rough conductors, through
// rough dielectrics narrower than alpha 0.1 or where ill-conditioned, and along such edges, are
// held to their median and 90th percentile, all others to every single value.
//
// The water caustic runs twice more with lax normals (as its benches and its reference render
// it): its 54771 vertex normals are all vertical while its facets tilt by 26 degrees at the
// median, so every Dirac lobe there turns about a normal that is not the geometry's, and light
// subpaths carry the adjoint correction (Veach 1997, eq. 5.17) through it. Once with its own
// small light, once with the light 200 times wider, where camera paths reach the light through
// the water: the strategies with no light vertex that carry everything under the water.
#include "common/transport/path.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "common/mcmc/primary_sample_integrand.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"
#include "common/scene/stiff_scenes.h"
#include "common/scene/test_scenes.h"
#include "common/transport/bidirectional.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;

// Where a rough dielectric's value at a vertex swings over the 1e-4 radians by which the edges
// differ from the sampled directions: a direction within a few degrees of grazing (microfacet
// shadowing varies as 1 / cos) or of its facet, a facet standing nearly upright (a small turn
// flips which side it faces), the critical angle (where 1 - F and the refracted cosine vanish
// with infinite slope), or an edge so short that the offsets turn it by far more than 1e-4.
bool illConditioned(const BsdfDescription& bsdf, const PathVertex& v, const Vec3f& from,
                    const Vec3f& to) {
  const Vec3f a = normalize(from - v.p), b = normalize(to - v.p);
  const float ca = dot(a, v.ns), cb = dot(b, v.ns);
  const float etaA = ca > 0 ? bsdf.extIOR : bsdf.intIOR, etaB = cb > 0 ? bsdf.extIOR : bsdf.intIOR;
  const Vec3f h = ca * cb > 0 ? normalize(a + b) : normalize(etaA * a + etaB * b);
  // The squared cosine of a's refraction through the facet (negative: totally reflected).
  const float etaOther = ca > 0 ? bsdf.intIOR : bsdf.extIOR, c = absDot(a, h);
  const float k = 1 - (etaA / etaOther) * (etaA / etaOther) * (1 - c * c);
  // Across a corner of the slab an edge is short, and the offsets turn it by more.
  const float shortest = std::sqrt(std::min(lengthSquared(from - v.p), lengthSquared(to - v.p)));
  return std::min({std::fabs(ca), std::fabs(cb), c, absDot(b, h), absDot(h, v.ns)}) < 0.05f ||
         std::fabs(k) < 0.01f || shortest < 0.05f;
}

// An edge whose geometric or shading cosine at either end is so small, or which is so short, that
// the ray's start offsetFor(p) off the surface may turn the cosine by 0.5% or more: the edge turns
// by about offset / length radians, which changes a cosine c by that over c. On the water under
// lax normals a ray refracted about the vertical can even strike the next facet micrometres away.
bool edgeIllConditioned(const Scene& scene, const PathVertex& a, const PathVertex& b) {
  const Vec3f d = b.p - a.p;
  const float len = length(d);
  if (!(len > 0)) return true;
  const Vec3f w = d / len;
  float c = 1;
  for (const PathVertex* v : {&a, &b}) {
    if (lengthSquared(v->n) > 0) c = std::min({c, absDot(v->n, w), absDot(v->ns, w)});
  }
  return scene.offsetFor(a.p) + scene.offsetFor(b.p) > 5e-3f * len * c;
}

void expectContributionsMatch(const std::string& name, std::shared_ptr<const Scene> scene = {},
                              int samples = 12000) {
  if (!scene) {
    RenderSettings settings;
    settings.width = 64;
    settings.height = 64;
    scene = loadScene(kShared + "/scenes/" + name + "/scene.xml", settings);
  }
  const int maxDepth = 4;
  BidirectionalTracer tracer(*scene, maxDepth);
  Rng rng(11, 7);
  IndependentSampler sampler(&rng);
  std::vector<double> pL(16), pE(16), glossyErrors, edgeErrors;
  std::vector<char> delta(16);
  int strategies = 0, specular = 0;
  for (int i = 0; i < samples; ++i) {
    Vec2f film = primarySampleFilmPoint(scene->camera(), sampler);
    tracer.visitStrategies(film, sampler, [&](const BidirectionalTracer::StrategyPath& sp) {
      Path x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
      PathContribution f = x.contribution(*scene, maxDepth);
      ASSERT_TRUE(f.carriesLight()) << name << " strategy (" << sp.s << ", " << sp.t << ")";
      x.densities(*scene, pL.data(), pE.data(), delta.data());
      const int n = int(x.vertices.size());
      double logP = 0;
      for (int j = 0; j < sp.s; ++j) logP += std::log(pL[size_t(j)]);
      for (int j = sp.s; j < n - 1; ++j) logP += std::log(pE[size_t(j)]);  // not the pinhole
      const double expected = std::exp(f.logLuminance - logP);
      const double actual = luminance(sp.unweighted);
      // f > 0 with a zero density (expected infinite) is as wrong as any other mismatch.
      const double error =
          std::isfinite(expected) ? std::fabs(actual - expected) / expected : INFINITY;
      bool glossy = false, edge = false;
      for (int j = 0; j + 1 < n; ++j) edge |= edgeIllConditioned(*scene, x[j], x[j + 1]);
      for (int j = 1; j + 1 < n; ++j) {
        specular += x.isSpecular(*scene, j);
        const int b = scene->description().shapes[size_t(x[j].shape)].bsdf;
        if (b < 0) continue;  // the scene's default, a diffuse
        const BsdfDescription& bsdf = scene->description().bsdfs[size_t(b)];
        glossy |= bsdf.type == BsdfDescription::Type::RoughConductor;
        if (bsdf.type == BsdfDescription::Type::RoughDielectric)
          glossy |= bsdf.alpha < 0.1f || illConditioned(bsdf, x[j], x[j - 1].p, x[j + 1].p);
      }
      if (glossy) {
        glossyErrors.push_back(error);
      } else if (edge) {
        edgeErrors.push_back(error);
      } else {
        EXPECT_LT(error, 1e-2) << name << " strategy (" << sp.s << ", " << sp.t << ")";
        Spectrum color = sp.unweighted / float(actual);
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(color[c], f.color[c], 1e-3f * (1 + f.color[c]))
              << name << " strategy (" << sp.s << ", " << sp.t << ")";
      }
      if (sp.t == 1) {  // light tracing splats where the path projects
        EXPECT_NEAR(sp.film.x, f.film.x, 1e-2f);
        EXPECT_NEAR(sp.film.y, f.film.y, 1e-2f);
      }
      ++strategies;

      Path y;
      ASSERT_TRUE(y.deserialize(x.serialize(), *scene));
      ASSERT_EQ(y.vertices.size(), x.vertices.size());
      EXPECT_EQ(y.contribution(*scene, maxDepth).logLuminance, f.logLuminance);
    });
  }
  EXPECT_GT(strategies, 1000) << name;
  if (name == "veach-bidir" || name.rfind("water-caustic", 0) == 0 || name == "mirror room") {
    EXPECT_GT(specular, 50) << name << ": too few specular vertices to test them";
  }
  if (!glossyErrors.empty()) {
    std::sort(glossyErrors.begin(), glossyErrors.end());
    EXPECT_GT(glossyErrors.size(), 200u) << name;
    EXPECT_LT(glossyErrors[glossyErrors.size() / 2], 1e-3) << name << " (median)";
    EXPECT_LT(glossyErrors[glossyErrors.size() * 9 / 10], 1e-2) << name << " (90th percentile)";
  }
  // Ill-conditioned edges are the exception: most paths are held to every value.
  EXPECT_LT(edgeErrors.size(), size_t(strategies) / 20) << name;
  if (edgeErrors.size() >= 10) {
    std::sort(edgeErrors.begin(), edgeErrors.end());
    EXPECT_LT(edgeErrors[edgeErrors.size() / 2], 1e-3) << name << " (ill-conditioned, median)";
    EXPECT_LT(edgeErrors[edgeErrors.size() * 9 / 10], 1e-2)
        << name << " (ill-conditioned, 90th percentile)";
  }
  std::printf("%s: %d strategies, %zu along ill-conditioned edges\n", name.c_str(), strategies,
              edgeErrors.size());
}

TEST(Path, ContributionOverDensityIsTheBidirectionalEstimate) {
  for (const char* name : {"cornell-box", "veach-mis", "veach-bidir", "water-caustic"})
    expectContributionsMatch(name);
}

// The water caustic under lax normals, with its own light and with one 200 times wider (see the
// top of the file). Only here do a Dirac vertex's directions lie on one side of its shading
// normal and on two of its facet: f with the lobe told by the facet's sides instead leaves 1332
// of these paths without light, and none of the strict water's.
TEST(Path, ContributionOverDensityThroughWaterWithLaxNormals) {
  RenderSettings settings;
  settings.width = 64;
  settings.height = 64;
  settings.shadingNormals = ShadingNormals::Lax;
  const std::string file = kShared + "/scenes/water-caustic/scene.xml";
  auto scene = loadScene(file, settings);
  ASSERT_FALSE(scene->strictNormals());
  expectContributionsMatch("water-caustic, lax normals", scene, 40000);
  SceneDescription wide = scene->description();
  widenAreaLights(wide, 200.0f);
  expectContributionsMatch("water-caustic, lax normals, light 200 times wider",
                           std::make_shared<Scene>(wide), 40000);
}

// The smooth conductor (a Dirac lobe) and the rough dielectric (radiance and importance forms of
// refraction through microfacets), in the stability suite's scenes.
TEST(Path, ContributionOverDensityThroughMetalAndRoughGlass) {
  expectContributionsMatch("mirror room",
                           std::make_shared<Scene>(stiff::room(
                               stiff::metalPlateRoom(BsdfDescription::Type::Conductor, 0), 64)));
  expectContributionsMatch("rough glass",
                           std::make_shared<Scene>(stiff::glassInFurnace(1.5f, 64, 0.3f)));
}

TEST(Path, DeserializeRefusesWhatIsNotAPathOfTheScene) {
  RenderSettings settings;
  settings.width = settings.height = 16;
  auto scene = loadScene(kShared + "/scenes/cornell-box/scene.xml", settings);
  Path x;
  EXPECT_FALSE(x.deserialize("", *scene));
  EXPECT_FALSE(x.deserialize("PTH1 and some garbage bytes", *scene));
  // A real path, then damaged: truncated, a shape out of range, a NaN coordinate.
  BidirectionalTracer tracer(*scene, 4);
  Rng rng(1, 1);
  IndependentSampler sampler(&rng);
  std::string bytes;
  while (bytes.empty()) {
    tracer.visitStrategies(primarySampleFilmPoint(scene->camera(), sampler), sampler,
                           [&](const BidirectionalTracer::StrategyPath& sp) {
                             if (bytes.empty())
                               bytes =
                                   Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t).serialize();
                           });
  }
  ASSERT_TRUE(x.deserialize(bytes, *scene));
  EXPECT_FALSE(x.deserialize(bytes.substr(0, bytes.size() - 1), *scene));
  std::string badShape = bytes;
  const int32_t huge = 1 << 30;
  // The first vertex: kind (1 byte), p, n, ns (36), uv (8), then its shape.
  std::memcpy(&badShape[8 + 1 + 44], &huge, sizeof(huge));
  EXPECT_FALSE(x.deserialize(badShape, *scene));
  std::string nan = bytes;
  const float qnan = std::nanf("");
  std::memcpy(&nan[8 + 1], &qnan, sizeof(qnan));  // the first vertex's x coordinate
  EXPECT_FALSE(x.deserialize(nan, *scene));
  std::string nanUv = bytes;
  std::memcpy(&nanUv[8 + 1 + 36], &qnan, sizeof(qnan));  // its texture coordinate u
  EXPECT_FALSE(x.deserialize(nanUv, *scene));
  // A camera vertex that is not the camera's point (a pinhole here).
  ASSERT_TRUE(x.deserialize(bytes, *scene));
  x.vertices.back().p.x += 1e-3f;
  EXPECT_FALSE(x.deserialize(x.serialize(), *scene));
}

// The environment's vertex at infinity round-trips, bit for bit, as x_0 only, a unit direction
// on the scene's environment light.
TEST(Path, DeserializeTakesTheEnvironmentsVertexAsTheLightEndOnly) {
  RenderSettings settings;
  settings.width = settings.height = 16;
  auto scene = loadScene(std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt", settings);
  ASSERT_GE(scene->lights().environmentLight(), 0);
  Path x;
  BidirectionalTracer tracer(*scene, 4);
  Rng rng(3, 3);
  IndependentSampler sampler(&rng);
  while (x.vertices.size() < 3) {
    tracer.visitStrategies(
        primarySampleFilmPoint(scene->camera(), sampler), sampler,
        [&](const BidirectionalTracer::StrategyPath& sp) {
          Path p = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
          if (x.vertices.size() < 3 && p.vertices.size() >= 3 && atInfinity(p[0])) x = p;
        });
  }
  Path y;
  ASSERT_TRUE(y.deserialize(x.serialize(), *scene));
  EXPECT_TRUE(atInfinity(y[0]));
  EXPECT_EQ(y.serialize(), x.serialize());
  EXPECT_EQ(y.contribution(*scene, 4).logLuminance, x.contribution(*scene, 4).logLuminance);
  Path bad = x;
  bad[0].n = bad[0].n * 2.0f;  // not a direction
  EXPECT_FALSE(y.deserialize(bad.serialize(), *scene));
  bad = x;
  bad[0].light = scene->lights().environmentLight() + 1;  // not the environment
  EXPECT_FALSE(y.deserialize(bad.serialize(), *scene));
  bad = x;
  bad[1] = x[0];  // at infinity in the middle of the path
  EXPECT_FALSE(y.deserialize(bad.serialize(), *scene));
}

// Through a thin lens the camera vertex is any point of the lens, and nothing off it.
TEST(Path, DeserializeTakesCameraVerticesOnTheLensOnly) {
  RenderSettings settings;
  auto scene = loadScene(std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt", settings);
  const Camera& camera = scene->camera();
  ASSERT_TRUE(camera.hasLens());
  Path x;
  BidirectionalTracer tracer(*scene, 3);
  Rng rng(2, 2);
  IndependentSampler sampler(&rng);
  while (x.vertices.empty()) {
    tracer.visitStrategies(primarySampleFilmPoint(camera, sampler), sampler,
                           [&](const BidirectionalTracer::StrategyPath& sp) {
                             if (x.vertices.empty())
                               x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
                           });
  }
  Path y;
  for (const Vec2f u : {Vec2f(0.5f, 0.5f), Vec2f(0, 0), Vec2f(1, 1), Vec2f(0.999f, 0.2f)}) {
    x.vertices.back().p = camera.lensPoint(u);
    EXPECT_TRUE(y.deserialize(x.serialize(), *scene)) << u.x << " " << u.y;
  }
  const float radius = scene->description().camera.lensRadius;
  x.vertices.back().p = camera.position() + Vec3f(1.01f * radius, 0, 0);  // beyond its rim
  EXPECT_FALSE(y.deserialize(x.serialize(), *scene));
  x.vertices.back().p = camera.lensPoint(Vec2f(0.5f, 0.5f)) + camera.forward() * 1e-3f;
  EXPECT_FALSE(y.deserialize(x.serialize(), *scene));  // off its plane
}

}  // namespace
}  // namespace farm
