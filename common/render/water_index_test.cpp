// The index series of issue 43, part 1: the water caustic at index 1.0001 against a reference
// that needs no photon mapping (below), at 1.1 to 4 against Tungsten's photon mapping
// (MltMeetsPhotonMappingAtEveryIndex), and a glass ball in the Cornell box at the same indices
// against BDPT (GlassBallIndex, further down).
//
// The water caustic at index 1.0001, against a reference that needs no photon
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

#include "common/film/image.h"
#include "common/render/local_render.h"
#include "common/render/render_job.h"
#include "common/scene/film_override.h"
#include "common/scene/loaders/scene_loader.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"

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

// count renders of d from seed firstSeed on; bootstrap candidates for the Markov chains' (0: the
// job's own count).
std::vector<Image> renders(const SceneDescription& d, Algorithm algorithm, int64_t budget,
                           int count, uint64_t firstSeed, int64_t bootstrap = 0) {
  std::vector<Image> images;
  for (int k = 0; k < count; ++k) {
    RenderSettings s;
    s.algorithm = algorithm;
    s.samplesPerPixel = s.mutationsPerPixel = budget;
    s.seed = firstSeed + uint64_t(k);
    s.bootstrapSamples = bootstrap;
    const LocalRenderResult r =
        renderLocally(RenderJob(std::make_shared<Scene>(d), s, "water-index"));
    EXPECT_EQ(r.rejected.total(), 0);
    images.push_back(r.image);
  }
  return images;
}

// The pixels other than the light's: those where the references' mean is below 20 times its
// median.
std::vector<bool> withoutTheLight(const std::vector<Image>& references) {
  std::vector<double> grey(size_t(kSide) * kSide, 0.0);
  for (const Image& image : references)
    for (size_t p = 0; p < grey.size(); ++p)
      grey[p] += (double(image.rgb[3 * p]) + image.rgb[3 * p + 1] + image.rgb[3 * p + 2]) / 3;
  std::vector<double> sorted = grey;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::vector<bool> keep(grey.size());
  for (size_t p = 0; p < grey.size(); ++p) keep[p] = grey[p] < 20 * median;
  return keep;
}

// mlt's renders against the reference renders over rows [first, kSide) of the pixels `keep`
// marks: their means, each side's standard error from its renders' spread (Z is shared by every
// pixel of a render, so the pixels' spread would understate it), printed under `name`; the
// difference's standard error is returned.
struct Comparison {
  Spread mlt, reference;
  double standardError = 0;
};
Comparison compareMeans(const std::vector<Image>& mlt, const std::vector<Image>& reference,
                        const std::vector<bool>& keep, int first, const std::string& name) {
  std::vector<double> mltMeans, referenceMeans;
  for (const Image& image : mlt) mltMeans.push_back(meanOver(image, keep, first, kSide));
  for (const Image& image : reference)
    referenceMeans.push_back(meanOver(image, keep, first, kSide));
  Comparison c;
  c.mlt = spreadOf(mltMeans), c.reference = spreadOf(referenceMeans);
  c.standardError = std::hypot(c.mlt.standardError, c.reference.standardError);
  const Spread &m = c.mlt, &r = c.reference;
  std::printf("%s: mlt %.5f (se %.2f%%), bdpt %.5f (se %.2f%%): %+.2f%%, %.1f standard errors\n",
              name.c_str(), m.mean, 100 * m.standardError / m.mean, r.mean,
              100 * r.standardError / r.mean, 100 * (m.mean / r.mean - 1),
              (m.mean - r.mean) / c.standardError);
  return c;
}

TEST(WaterIndex, MltNearIndexOneMeetsTheRoomWithoutItsWater) {
  const std::vector<Image> dry =
      renders(waterCaustic(1.0001, true), Algorithm::Bidirectional, 512, 4, 301);
  const std::vector<Image> wet = renders(waterCaustic(1.0001, false), Algorithm::MLT, 1024, 6, 401);
  const std::vector<bool> keep = withoutTheLight(dry);
  // The image, and the rows below its top quarter (the floor and walls seen through the water).
  for (auto [first, name] :
       {std::pair{0, "the image"}, std::pair{kSide / 4, "through the water"}}) {
    const Comparison c = compareMeans(
        wet, dry, keep, first, std::string("water at 1.0001 (the dry room's bdpt), ") + name);
    EXPECT_NEAR(c.mlt.mean, c.reference.mean, 4 * c.standardError) << name;
  }
}

// The water caustic at the other indices (1.1, 1.33, 1.5, 2.4 and 4) and the one it ships
// with (1.8), lax and unbounded as above, against Tungsten's progressive photon mapping:
// tests/data/water-index holds the mean of three 128x128 renders of 64 passes each, averaged down
// to 32x32 (tools/water_index_references.py; their standard error and measured bias are at most
// 0.2% a channel, docs/specular.md), folded in here as a standard error of 0.3% of the reference's
// mean. The light's pixels and their neighbours are left out, chosen by the reference alone (each
// renderer's pixel filter spreads the light its own way). Z from 2^15 candidates each. The issue
// measured mlt 6-7% dark at 4 and 5.8% at 1.0001; here every index comes within 1.5 standard
// errors (0.2-0.8%). Seen failing with a refraction's Dirac Jacobian 10% high (-1.5% to
// -7.5%, four of five indices past 4 standard errors) and with manifold next-event estimation's
// trials counted one too many (+11% to +64%).
TEST(WaterIndex, MltMeetsPhotonMappingAtEveryIndex) {
  for (const char* index : {"1.1", "1.33", "1.5", "1.8", "2.4", "4"}) {
    Image reference;
    std::string error;
    ASSERT_TRUE(readExr(std::string(FARM_TEST_DATA_DIR) + "/water-index/" + index + ".exr",
                        &reference, &error))
        << error;
    ASSERT_EQ(reference.width, kSide);
    ASSERT_EQ(reference.height, kSide);
    // The light's pixels: above ten times the image's mean (two at every index; the median,
    // withoutTheLight's yardstick, falls to a sixtieth of the mean at index 4, where the floor
    // under the water goes dark), and their neighbours.
    double mean = 0;
    for (size_t p = 0; p < size_t(kSide) * kSide; ++p)
      mean += (double(reference.rgb[3 * p]) + reference.rgb[3 * p + 1] + reference.rgb[3 * p + 2]) /
              (3.0 * kSide * kSide);
    std::vector<bool> kept(size_t(kSide) * kSide, true);
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const size_t p = size_t(y) * kSide + x;
        if ((double(reference.rgb[3 * p]) + reference.rgb[3 * p + 1] + reference.rgb[3 * p + 2]) /
                3 <
            10 * mean)
          continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (x + dx >= 0 && x + dx < kSide && y + dy >= 0 && y + dy < kSide)
              kept[size_t(y + dy) * kSide + x + dx] = false;
      }
    const std::vector<Image> mlt =
        renders(waterCaustic(std::stod(index), false), Algorithm::MLT, 1024, 6, 701, 1 << 15);
    std::vector<double> means;
    for (const Image& image : mlt) means.push_back(meanOver(image, kept, 0, kSide));
    const Spread m = spreadOf(means);
    const double r = meanOver(reference, kept, 0, kSide);
    const double standardError = std::hypot(m.standardError, 0.003 * r);
    std::printf(
        "water at %s: mlt %.5f (se %.2f%%), photon mapping %.5f: %+.2f%%, %.1f standard "
        "errors\n",
        index, m.mean, 100 * m.standardError / m.mean, r, 100 * (m.mean / r - 1),
        (m.mean - r) / standardError);
    EXPECT_NEAR(m.mean, r, 4 * standardError) << "index " << index;
    EXPECT_LT(m.standardError, 0.02 * r) << "index " << index << ": too noisy to tell";
  }
}

// A glass ball on the Cornell box's floor (bench/glass_ball_index.py's, radius 0.25) at the
// issue's indices, from nearly none to an extreme one: under the box's large light BDPT converges
// on everything the ball makes (its caustic, the floor through it, the light's glints), so its
// renders are the reference, and mlt's (manifold perturbations through the ball, manifold
// next-event estimation in its bootstrap) must meet them within 4 standard errors of the difference
// in the image's mean, the light's pixels left out. At 128x128 and 60 s each index came within 0.4%
// (docs/specular.md). Seen failing with the specular chain's determinant left out of its measure
// ratio (+2.5%, +22% and +46%: 11, 101 and 229 standard errors); a ratio 10% off is not caught
// (-0.4% at most): the ball's chains are a small share of the whole image's mean.
TEST(GlassBallIndex, MltMeetsBdptAtEveryIndex) {
  for (double ior : {1.0001, 1.1, 1.33, 1.5, 2.4, 4.0}) {
    SceneDescription d = loadSceneDescription(kShared + "/scenes/cornell-box/scene.xml");
    applyFilmOverride(d, kSide, kSide);
    d.maxDepth = -1;
    BsdfDescription glass;
    glass.type = BsdfDescription::Type::Dielectric;
    glass.intIOR = float(ior), glass.extIOR = 1;
    d.bsdfs.push_back(glass);
    d.shapes.push_back(sphereShape(Vec3f(-0.45f, 0.25f, 0.5f), 0.25f, int(d.bsdfs.size()) - 1));
    const std::vector<Image> bdpt = renders(d, Algorithm::Bidirectional, 256, 4, 501);
    // 2^16 candidates: at the job's own count (a few thousand at this size) Z is skewed, most
    // renders a little low and a few high, and six renders' spread understates its error
    // (docs/specular.md; the pilot's bias that also made them low is mended).
    const std::vector<Image> mlt = renders(d, Algorithm::MLT, 512, 6, 601, 1 << 16);
    const std::vector<bool> keep = withoutTheLight(bdpt);
    const Comparison c = compareMeans(mlt, bdpt, keep, 0, "glass ball at " + std::to_string(ior));
    EXPECT_NEAR(c.mlt.mean, c.reference.mean, 4 * c.standardError) << "index " << ior;
    EXPECT_LT(c.standardError, 0.02 * c.reference.mean) << "index " << ior << ": too noisy to tell";
  }
}

}  // namespace
}  // namespace farm
