// The transition densities T(y | x) of the mutations are the densities their proposals have,
// checked against answers that do not come from the mutation's own sampling code:
//  - the bidirectional mutation, by the importance-sampling identity: when it deletes all but
//    the camera and regrows na vertices, E[f(y) / T(y | x)] over its proposals is the integral of
//    the luminance of f over all paths of na edges, which BDPT estimates on its own, length by
//    length (on the Cornell box; around glass the mutation regrows most path kinds too rarely
//    for this estimate to be sharp, and the densities through Dirac lobes that it sums are the
//    ones Path's own test checks against BDPT);
//  - the lens and caustic perturbations, by their normalization: the density of the moved
//    vertex over the wall it lands on integrates to one (the perturbation always lands there), the
//    integral taken by sampling points of the wall in polar coordinates about the old vertex,
//    a parameterization of the wall and not of the film or of directions.
// Bounds: 4.4 standard errors, about 1e-4 two-sided per comparison.
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "common/mcmc/mutations/bidirectional_mutation.h"
#include "common/mcmc/mutations/caustic_perturbation.h"
#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/bidirectional.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;
constexpr double kZ = 4.4;

std::shared_ptr<Scene> load(const std::string& file, int size) {
  RenderSettings settings;
  settings.width = settings.height = size;
  return loadScene(file, settings);
}

int maxDepthOf(const Scene& scene) {
  return scene.maxDepth() == 0 ? -1 : scene.maxDepth();
}

// The first BDPT strategy path (in sample order) that `accept` likes.
template <typename Accept>
Path findPath(const Scene& scene, int maxDepth, Accept accept) {
  Rng rng(5, 5);
  IndependentSampler sampler(&rng);
  BidirectionalTracer tracer(scene, maxDepth);
  for (int i = 0; i < 1000000; ++i) {
    Path found;
    tracer.visitStrategies(primarySampleFilmPoint(scene.camera(), sampler), sampler,
                           [&](const BidirectionalTracer::StrategyPath& sp) {
                             if (!found.vertices.empty()) return;
                             Path x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
                             if (x.contribution(scene, maxDepth).carriesLight() && accept(x))
                               found = x;
                           });
    if (!found.vertices.empty()) return found;
  }
  throw std::runtime_error("no such path");
}

struct Estimate {
  double mean = 0, stdError = 0;
};

// --- The bidirectional mutation against BDPT, path length by path length --------------------

void expectPathLengthIntegrals(const std::string& file, int lengths, int proposalCount = 1 << 19) {
  auto scene = load(file, 24);
  const int maxDepth = maxDepthOf(*scene);
  // BDPT: per sample, the luminance its strategies carry, by path length.
  const int samples = 1 << 19;
  std::vector<std::vector<double>> perSample(samples, std::vector<double>(lengths + 1, 0.0));
  tbb::parallel_for(0, samples, [&](int i) {
    Rng rng(31, uint64_t(i));
    IndependentSampler sampler(&rng);
    BidirectionalTracer tracer(*scene, maxDepth);
    tracer.visitStrategies(primarySampleFilmPoint(scene->camera(), sampler), sampler,
                           [&](const BidirectionalTracer::StrategyPath& sp) {
                             int k = sp.s + sp.t - 1;
                             if (k <= lengths)
                               perSample[i][k] += luminance(sp.unweighted) * sp.weight;
                           });
  });
  // The mutation: from a path of three vertices, the proposals that delete both non-camera
  // vertices (through a thin lens: all three, the lens point regrown too); f / T of each, over
  // all proposals made, by the length regrown.
  const int keptCamera = scene->camera().hasLens() ? 0 : 1;
  MutationContext context{*scene, maxDepth};
  BidirectionalMutation mutation(context);
  const Path x = findPath(*scene, maxDepth, [](const Path& p) { return p.length() == 2; });
  const int proposals = proposalCount;
  const int tasks = 64;
  std::vector<std::vector<double>> sum(tasks, std::vector<double>(lengths + 1, 0.0)), sumSq = sum;
  tbb::parallel_for(0, tasks, [&](int task) {
    Rng rng(17, uint64_t(task));
    for (int i = 0; i < proposals / tasks; ++i) {
      Path y;
      MutationRecord r;
      double v = 0;
      int k = 0;
      if (mutation.propose(x, rng, &y, &r) && r.keptLight == 0 && r.keptCamera == keptCamera &&
          y.length() <= lengths) {
        PathContribution fy = y.contribution(*scene, maxDepth);
        if (fy.carriesLight()) {
          k = y.length();
          v = std::exp(fy.logLuminance - mutation.logDensity(x, y, r));
        }
      }
      // Every proposal counts, with zero where it is not of this kind.
      for (int j = 1; j <= lengths; ++j) {
        double value = j == k ? v : 0.0;
        sum[task][j] += value;
        sumSq[task][j] += value * value;
      }
    }
  });
  for (int k = 1; k <= lengths; ++k) {
    Estimate bdpt, mutated;
    double s = 0, s2 = 0;
    for (const auto& v : perSample) s += v[k], s2 += v[k] * v[k];
    bdpt.mean = s / samples;
    bdpt.stdError = std::sqrt(std::max(0.0, s2 / samples - bdpt.mean * bdpt.mean) / samples);
    s = s2 = 0;
    for (int t = 0; t < tasks; ++t) s += sum[t][k], s2 += sumSq[t][k];
    mutated.mean = s / proposals;
    mutated.stdError =
        std::sqrt(std::max(0.0, s2 / proposals - mutated.mean * mutated.mean) / proposals);
    if (bdpt.mean == 0) {  // no path of this length carries light (a point light unseen)
      EXPECT_EQ(mutated.mean, 0) << file << ", paths of " << k << " edges";
      continue;
    }
    const double se = std::hypot(bdpt.stdError, mutated.stdError);
    EXPECT_NEAR(mutated.mean, bdpt.mean, kZ * se) << file << ", paths of " << k << " edges";
    EXPECT_LT(se, 0.05 * bdpt.mean) << "too noisy to tell at length " << k;
    std::printf("%s, %d edges: mutation %.5g +- %.2g, bdpt %.5g +- %.2g\n",
                std::filesystem::path(file).filename().c_str(), k, mutated.mean, mutated.stdError,
                bdpt.mean, bdpt.stdError);
  }
}

TEST(BidirectionalMutationDensity, RegrowsEveryPathLengthAsBidirectionalPathTracingSeesIt) {
  expectPathLengthIntegrals(kShared + "/scenes/cornell-box/scene.xml", 4);
}

// Light vertices from a spot light (its position and its cone of directions) and from both
// sides of a two-sided area light hanging in the middle of the box: their densities are the ones
// BDPT's MIS uses, which BDPT's own integrals check.
TEST(BidirectionalMutationDensity, RegrowsPathsFromPointAndTwoSidedLights) {
  const std::string spot = litBoxScene(
      "LightSource \"spot\" \"rgb I\" [4 4 4] \"point from\" [0 2.8 1] \"point to\" "
      "[0.3 0 1.5] \"float coneangle\" 50 \"float conedeltaangle\" 10\n");
  const std::string twoSided = litBoxScene(
      "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 3] \"bool twosided\" true\n"
      "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.4 2.4 1.2  "
      "0.4 2.4 1.2  0.4 2.4 2  -0.4 2.4 2]\nAttributeEnd\n");
  expectPathLengthIntegrals(spot, 4);
  expectPathLengthIntegrals(twoSided, 4);
  std::filesystem::remove(spot);
  std::filesystem::remove(twoSided);
}

// Vertices in media: the smoke room of tests/data (fog below, a grid of smoke filling the room
// above it, so that regrown paths scatter in both), where BDPT's integrals over each path length
// are its own estimates through the media (which path tracing's check) and the mutation's are
// E[f / T] with its free flights' densities in T and the transmittances (marched finely) in f.
TEST(BidirectionalMutationDensity, RegrowsPathsWithVerticesInMedia) {
  expectPathLengthIntegrals(std::string(FARM_TEST_DATA_DIR) + "/smoke-room/scene.xml", 4, 1 << 21);
}

// Through a thin lens the mutation can regrow the camera's end from a new lens point, and the
// whole path so: E[f / T] over those proposals is then BDPT's integral over the lens too
// (tests/data/thin-lens, with its lens of radius 0.4 across a view of 64 x 32 pixels).
TEST(BidirectionalMutationDensity, RegrowsPathsThroughAThinLensFromNewLensPoints) {
  expectPathLengthIntegrals(std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt", 3);
}

// Under an image sky (tests/data/sky: a floor and two balls, one glossy): light vertices on
// the environment (a direction by the map's importance, then the disk facing it), camera
// subpaths that end on it where their rays leave the scene, and edges to it along its
// direction.
TEST(BidirectionalMutationDensity, RegrowsPathsFromTheEnvironment) {
  expectPathLengthIntegrals(std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt", 3, 1 << 22);
}

// --- The perturbations integrate to one -------------------------------------------------------

// Integral over the plane of x's vertex `moved` of T(y | x), where y is x with that vertex moved
// to a point of the plane: points drawn log-uniformly in distance (rho1 .. rho2) and uniformly in
// angle about the old position, so that T / q stays bounded where T piles up near it.
Estimate integrateOverPlane(const Mutation& mutation, const Path& x, const MutationRecord& record,
                            int moved, double rho1, double rho2, int samples) {
  const PathVertex& v = x[moved];
  Frame plane(v.n);
  double sum = 0, sumSq = 0;
  Rng rng(9, 9);
  for (int i = 0; i < samples; ++i) {
    const double rho = rho1 * std::exp(std::log(rho2 / rho1) * rng.nextDouble());
    const double phi = 2 * M_PI * rng.nextDouble();
    const double q = 1 / (2 * M_PI * rho * rho * std::log(rho2 / rho1));
    Path y = x;
    y[moved].p = v.p + plane.s * float(rho * std::cos(phi)) + plane.t * float(rho * std::sin(phi));
    const double t = std::exp(mutation.logDensity(x, y, record));
    sum += t / q;
    sumSq += (t / q) * (t / q);
  }
  Estimate e;
  e.mean = sum / samples;
  e.stdError = std::sqrt(std::max(0.0, sumSq / samples - e.mean * e.mean) / samples);
  return e;
}

// A Cornell box path seen on the back wall near the image's centre, the wall around it open to
// the camera and to the vertex before it.
Path backWallPath(const Scene& scene, int maxDepth) {
  const Camera& camera = scene.camera();
  return findPath(scene, maxDepth, [&](const Path& x) {
    const int k = x.length();
    if (k < 2 || x.isSpecular(scene, k - 1)) return false;
    const PathVertex& v = x[k - 1];
    if (absDot(v.n, camera.forward()) < 0.99f) return false;  // square to the camera
    Vec2f film;
    if (!camera.project(camera.position(), normalize(v.p - camera.position()), &film)) return false;
    return std::fabs(film.x - 0.5f * camera.width()) < 2 && film.y < 0.45f * camera.height() &&
           film.y > 0.3f * camera.height();
  });
}

// A back-wall path of the Cornell box and a perturbation of its last vertex; `reach` gives the
// radii on the wall between which its density lives.
template <typename Perturbation, typename Reach>
void expectIntegratesToOne(MutationType type, Reach reach) {
  auto scene = load(kShared + "/scenes/cornell-box/scene.xml", 64);
  const int maxDepth = maxDepthOf(*scene);
  const Path x = backWallPath(*scene, maxDepth);
  MutationContext context{*scene, maxDepth};
  Perturbation perturbation(context);
  ASSERT_TRUE(perturbation.appliesTo(x));
  const int k = x.length();
  const MutationRecord record{type, k - 1, 1, 1, 1};
  double rho1, rho2;
  reach(perturbationSizes(scene->camera()), x, &rho1, &rho2);
  Estimate e = integrateOverPlane(perturbation, x, record, k - 1, rho1, rho2, 1 << 18);
  EXPECT_NEAR(e.mean, 1.0, kZ * e.stdError + 1e-3) << "standard error " << e.stdError;
  EXPECT_LT(e.stdError, 0.01);
  std::printf("%s: integral %.5f +- %.5f\n", mutationName(type), e.mean, e.stdError);
}

TEST(PerturbationDensity, LensPerturbationIntegratesToOne) {
  // One pixel on the wall, and the perturbation's reach: 0.1 to about 11 pixels.
  expectIntegratesToOne<LensPerturbation>(
      MutationType::LensPerturbation,
      [](const PerturbationSizes& sizes, const Path& x, double* rho1, double* rho2) {
        const int k = x.length();
        const double pixel = double(length(x[k - 1].p - x[k].p)) * sizes.theta1 / sizes.r1;
        *rho1 = 0.02 * pixel;
        *rho2 = 3 * sizes.r2 * pixel;
      });
}

TEST(PerturbationDensity, CausticPerturbationIntegratesToOne) {
  // The cone of directions from x_{k-2}, as wide as the largest angle on the wall.
  expectIntegratesToOne<CausticPerturbation>(
      MutationType::CausticPerturbation,
      [](const PerturbationSizes& sizes, const Path& x, double* rho1, double* rho2) {
        const int k = x.length();
        const double distance = double(length(x[k - 1].p - x[k - 2].p));
        const double scale = double(length(x[k].p - x[k - 1].p)) / distance;
        const double cosine =
            std::fabs(double(dot(x[k - 1].n, normalize(x[k - 1].p - x[k - 2].p))));
        *rho1 = 0.02 * sizes.theta1 * scale * distance;
        *rho2 = 3 * sizes.theta2 * scale * distance / cosine;
      });
}

}  // namespace
}  // namespace farm
