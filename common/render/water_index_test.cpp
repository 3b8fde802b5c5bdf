// The water caustic at index 1.0001 (issue 43, part 1), against a reference that needs no photon
// mapping: near index 1 the water vanishes (Fresnel reflectance ~1e-9 at normal incidence,
// refraction bending a ray by ~1e-4 rad), so the shared scene with its water taken out, which
// BDPT renders well, is the limit the water's image converges to. The water's smooth-shaded
// waves make the manifold walk's constraint nearly degenerate there (the generalized half vector
// of a refraction shrinks with eta - 1): what the issue feared would leave mlt dark.
//
// Both scenes at an unbounded depth: each crossing of the water is an edge, so at a bounded depth
// the water's paths are cut where the dry room's are not (docs/specular.md: 4-8% at 8 edges).
// mlt's renders, each with its own seed, against the mean of bdpt's renders of the dry room: the
// means of the image and of the part seen through the water, within 4 standard errors of the
// difference (each side's from its renders' spread: the bootstrap's Z is shared by every pixel
// of a render, so the pixels' spread would understate it). The light's own pixels are left out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/film_override.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/scene.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;
constexpr int kSide = 32;

// The shared water caustic, lax, unbounded, kSide x kSide, its water at `ior` or taken out.
SceneDescription waterCaustic(double ior, bool dry) {
  SceneDescription d = loadSceneDescription(kShared + "/scenes/water-caustic/scene.xml");
  applyFilmOverride(d, kSide, kSide);
  d.strictNormals = false;
  d.maxDepth = -1;
  int water = -1;
  for (size_t b = 0; b < d.bsdfs.size(); ++b)
    if (d.bsdfs[b].type == BsdfDescription::Type::Dielectric) water = int(b);
  EXPECT_GE(water, 0) << "the shared scene has no water";
  d.bsdfs[size_t(water)].intIOR = float(ior);
  if (dry) {
    d.shapes.erase(std::remove_if(d.shapes.begin(), d.shapes.end(),
                                  [&](const ShapeDescription& s) { return s.bsdf == water; }),
                   d.shapes.end());
  }
  return d;
}

// The grey mean over the rows [first, last) of the pixels `keep` marks.
double meanOver(const Image& image, const std::vector<bool>& keep, int first, int last) {
  double sum = 0;
  int count = 0;
  for (int y = first; y < last; ++y)
    for (int x = 0; x < kSide; ++x) {
      const size_t p = size_t(y) * kSide + x;
      if (!keep[p]) continue;
      sum += (double(image.rgb[3 * p]) + image.rgb[3 * p + 1] + image.rgb[3 * p + 2]) / 3;
      ++count;
    }
  return sum / count;
}

struct Spread {
  double mean = 0, standardError = 0;
};

Spread spreadOf(const std::vector<double>& v) {
  Spread s;
  for (double x : v) s.mean += x / double(v.size());
  double var = 0;
  for (double x : v) var += (x - s.mean) * (x - s.mean) / double(v.size() - 1);
  s.standardError = std::sqrt(var / double(v.size()));
  return s;
}

std::vector<Image> renders(const SceneDescription& d, Algorithm algorithm, int64_t budget,
                           int count, uint64_t firstSeed) {
  std::vector<Image> images;
  for (int k = 0; k < count; ++k) {
    RenderSettings s;
    s.algorithm = algorithm;
    s.samplesPerPixel = s.mutationsPerPixel = budget;
    s.seed = firstSeed + uint64_t(k);
    const LocalRenderResult r =
        renderLocally(RenderJob(std::make_shared<Scene>(d), s, "water-index"));
    EXPECT_EQ(r.rejected.total(), 0);
    images.push_back(r.image);
  }
  return images;
}

TEST(WaterIndex, MltNearIndexOneMeetsTheRoomWithoutItsWater) {
  const std::vector<Image> dry =
      renders(waterCaustic(1.0001, true), Algorithm::Bidirectional, 512, 4, 301);
  const std::vector<Image> wet = renders(waterCaustic(1.0001, false), Algorithm::MLT, 1024, 6, 401);
  // Leave out the light's pixels: those where the dry room's mean is over 20 times its median.
  std::vector<double> grey(size_t(kSide) * kSide, 0.0);
  for (const Image& image : dry)
    for (size_t p = 0; p < grey.size(); ++p)
      grey[p] += (double(image.rgb[3 * p]) + image.rgb[3 * p + 1] + image.rgb[3 * p + 2]) / 3;
  std::vector<double> sorted = grey;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::vector<bool> keep(grey.size());
  for (size_t p = 0; p < grey.size(); ++p) keep[p] = grey[p] < 20 * median;
  // The image, and the rows below its top quarter (the floor and walls seen through the water).
  for (auto [first, name] :
       {std::pair{0, "the image"}, std::pair{kSide / 4, "through the water"}}) {
    std::vector<double> dryMeans, wetMeans;
    for (const Image& image : dry) dryMeans.push_back(meanOver(image, keep, first, kSide));
    for (const Image& image : wet) wetMeans.push_back(meanOver(image, keep, first, kSide));
    const Spread d = spreadOf(dryMeans), w = spreadOf(wetMeans);
    const double se = std::hypot(d.standardError, w.standardError);
    std::printf(
        "water at 1.0001, %s: mlt %.5f (se %.2f%%), the dry room's bdpt %.5f (se %.2f%%): "
        "%+.2f%%, %.1f standard errors\n",
        name, w.mean, 100 * w.standardError / w.mean, d.mean, 100 * d.standardError / d.mean,
        100 * (w.mean / d.mean - 1), (w.mean - d.mean) / se);
    EXPECT_NEAR(w.mean, d.mean, 4 * se) << name;
  }
}

}  // namespace
}  // namespace farm
