// Path-space MLT is exact, mutation by mutation:
//  - detailed balance: for thousands of paths of the shared scenes and a glass scene, every
//    proposal y of every mutation satisfies f(x) T(y|x) a(y|x) = f(y) T(x|y) a(x|y) to rounding,
//    with T(x|y) evaluated from y by the reverse move (and finite wherever y carries light);
//  - stationarity: each mutation alone, run from seeds drawn from the target (the bootstrap's
//    resampled BDPT paths), deposits its splats in the target's proportions: per block of the
//    image, the mean share over many independent chains agrees with the converged reference
//    (the Cornell box) or with a long BDPT render (glass, sky, water) within a Bonferroni bound at
//    level 1e-4, the standard errors taken from the spread of the chains and of the BDPT samples;
//  - a chain resumed from a flush's state continues bit for bit.
#include "common/mcmc/mlt_chain.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "common/chain/resume_check.h"
#include "common/film/image.h"
#include "common/mcmc/chain_statistics.h"
#include "common/mcmc/mutations/bidirectional_mutation.h"
#include "common/mcmc/mutations/caustic_perturbation.h"
#include "common/mcmc/mutations/lens_perturbation.h"
#include "common/mcmc/mutations/lens_subpath_mutation.h"
#include "common/mcmc/mutations/manifold_perturbation.h"
#include "common/mcmc/mutations/multi_chain_perturbation.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"
#include "common/scene/test_scenes.h"
#include "common/transport/bidirectional.h"
#include "common/transport/path_tracer.h"

namespace farm {
namespace {

const std::string kShared = FARM_SHARED_DIR;
constexpr double kAlpha = 1e-4;
constexpr int kFilm = 32, kBlocks = 4;

std::shared_ptr<Scene> loadSmall(const std::string& file) {
  RenderSettings settings;
  settings.width = settings.height = kFilm;
  auto loaded = loadScene(file, settings);
  SceneDescription desc = loaded->description();
  desc.camera.filter = FilterType::Box;  // pixels sum into blocks exactly
  return std::make_shared<Scene>(desc);
}

std::string cornellBox() {
  return kShared + "/scenes/cornell-box/scene.xml";
}

int maxDepthOf(const Scene& scene) {
  return scene.maxDepth() == 0 ? -1 : scene.maxDepth();
}

// Seeds from the production bootstrap: BDPT candidates resampled by luminance, then one of each
// candidate's strategy paths by its share.
BootstrapResult bootstrapSeeds(const std::shared_ptr<Scene>& scene, int chains, uint64_t seed) {
  RenderSettings settings;
  settings.algorithm = Algorithm::MLT;
  settings.numChains = chains;
  settings.bootstrapSamples = int64_t(1) << 18;
  settings.seed = seed;
  RenderJob job(scene, settings, "seeds");
  return job.bootstrap();
}

struct Mutations {
  explicit Mutations(const MutationContext& c)
      : bidirectional(c), lensSubpath(c), lens(c), caustic(c), multiChain(c), manifold(c) {}
  const Mutation* get(MutationType t) const {
    const Mutation* all[] = {&bidirectional, &lensSubpath, &lens, &caustic, &multiChain, &manifold};
    return all[int(t)];
  }
  BidirectionalMutation bidirectional;
  LensSubpathMutation lensSubpath;
  LensPerturbation lens;
  CausticPerturbation caustic;
  MultiChainPerturbation multiChain;
  ManifoldPerturbation manifold;
};

// --- Detailed balance ------------------------------------------------------------------------

void expectDetailedBalance(const std::string& file, int minimumChecked, bool specular = true) {
  auto scene = loadSmall(file);
  const int maxDepth = maxDepthOf(*scene);
  BootstrapResult seeds = bootstrapSeeds(scene, 2000, 3);
  MutationContext context{*scene, maxDepth};
  Mutations mutations(context);
  Rng rng(21, 21);
  for (int t = 0; t < kMutationTypes; ++t) {
    const Mutation& mutation = *mutations.get(MutationType(t));
    int checked = 0, irreversible = 0;
    for (const std::string& bytes : seeds.seedPaths) {
      Path x;
      ASSERT_TRUE(x.deserialize(bytes, *scene));
      PathContribution fx = x.contribution(*scene, maxDepth);
      ASSERT_TRUE(fx.carriesLight());
      if (!mutation.appliesTo(x)) continue;
      for (int attempt = 0; attempt < 4; ++attempt) {
        Path y;
        MutationRecord record;
        if (!mutation.propose(x, rng, &y, &record)) continue;
        PathContribution fy = y.contribution(*scene, maxDepth);
        if (!fy.carriesLight()) continue;
        ASSERT_TRUE(mutation.appliesTo(y)) << mutationName(MutationType(t));
        const double logTyx = mutation.logDensity(x, y, record);
        const double logTxy = mutation.logDensity(y, x, record.reverse());
        ASSERT_TRUE(std::isfinite(logTyx)) << mutationName(MutationType(t)) << ": T(y|x)";
        if (!std::isfinite(logTxy)) {
          // A move that cannot be undone (the bidirectional mutation deleted a specular run
          // that no connection can regrow; the caustic perturbation's angle lies outside the
          // range y's geometry allows) must not be accepted: both sides of the balance are 0.
          EXPECT_EQ(logAcceptanceRatio(mutation, x, fx, y, fy, record, 1, 1), -INFINITY);
          ++irreversible;
          continue;
        }
        const double logAxy =
            std::min(0.0, logAcceptanceRatio(mutation, x, fx, y, fy, record, 1, 1));
        const double logAyx =
            std::min(0.0, logAcceptanceRatio(mutation, y, fy, x, fx, record.reverse(), 1, 1));
        const double forward = fx.logLuminance + logTyx + logAxy;
        const double backward = fy.logLuminance + logTxy + logAyx;
        EXPECT_NEAR(forward, backward, 1e-9 * (1 + std::fabs(forward)))
            << mutationName(MutationType(t));
        ++checked;
      }
    }
    std::printf("%s, %s: %d proposals checked, %d not reversible\n",
                std::filesystem::path(file).filename().c_str(), mutationName(MutationType(t)),
                checked, irreversible);
    EXPECT_LE(irreversible, checked / 10) << mutationName(MutationType(t));
    // The Cornell box and the thin lens's boards have no specular surface for the multi-chain
    // and manifold perturbations.
    const bool specularOnly = t == int(MutationType::MultiChainPerturbation) ||
                              t == int(MutationType::ManifoldPerturbation);
    if (!specularOnly || specular) {
      EXPECT_GE(checked, minimumChecked) << mutationName(MutationType(t));
    }
  }
}

TEST(MltChain, DetailedBalanceCornellBox) {
  expectDetailedBalance(cornellBox(), 1000, false);
}
// Moves that regrow the lens point (the bidirectional mutation deleting the camera's end, the
// lens subpath mutation) are undone by moves of the same kind.
// Paths from the environment (tests/data/sky): its vertex at infinity regrown from either side,
// and kept while the perturbations move what follows it. Most of its paths are the sky seen
// directly or off one surface, which the caustic perturbation leaves alone (no point to perturb
// the sky's direction at): 78 of its proposals are checked, the others' several hundred. The
// bidirectional mutation's irreversible moves (7%) put a vertex between the camera and the sky
// it sees; the reverse would join the sky's direction to the camera, which no strategy does.
TEST(MltChain, DetailedBalanceUnderAnImageSky) {
  expectDetailedBalance(std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt", 50, false);
}
// (Most bidirectional proposals there carry no light: 920 of 8000 do.)
TEST(MltChain, DetailedBalanceThinLens) {
  expectDetailedBalance(std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt", 500, false);
}
TEST(MltChain, DetailedBalanceGlassBall) {
  expectDetailedBalance(glassBallScene(), 100);
}

// --- Stationarity, one mutation at a time ---------------------------------------------------
//
// A kernel keeps its target: chains started from independent draws of it deposit, on average,
// the target's share of luminance in every block of the image, however little they mix (the
// perturbations never move the light end of a path). The draws come from importance resampling
// of BDPT samples (a sample by its luminance, then one of its strategies' paths by its share),
// the measure the bootstrap seeds from, which converges to the target; its own block shares are
// a ratio estimate from those samples, whose standard error (delta method) joins the chains'.

int blockOf(const Vec2f& film) {
  int x = std::min(int(film.x) * kBlocks / kFilm, kBlocks - 1);
  int y = std::min(int(film.y) * kBlocks / kFilm, kBlocks - 1);
  return x + kBlocks * y;
}

struct Shares {
  std::vector<double> mean, stdError;
};

// BDPT samples: the block shares of their splats' luminance with standard errors, and each
// sample's total luminance, from which seeds are drawn.
struct ResampledTarget {
  Shares shares;
  std::vector<double> cumulative;  // running sum of the samples' totals
  uint64_t seed = 77;
  // When given, the target is the paths it keeps alone: the strategies' paths it refuses are
  // neither counted nor drawn.
  std::function<bool(const Path&)> keep;
};

// Shares of bins from independent samples (perSample[sample][bin]): each bin's total over the
// grand total, a ratio estimate whose standard error is the delta method's, share_b = m_b / m
// with variance var(X_b - share_b X) / (N m^2). *totals receives each sample's total.
Shares ratioShares(const std::vector<std::vector<double>>& perSample, std::vector<double>* totals) {
  const size_t samples = perSample.size(), bins = perSample.front().size();
  Shares s;
  s.mean.assign(bins, 0.0);
  s.stdError.assign(bins, 0.0);
  totals->assign(samples, 0.0);
  double total = 0;
  for (size_t i = 0; i < samples; ++i) {
    for (size_t b = 0; b < bins; ++b) s.mean[b] += perSample[i][b], (*totals)[i] += perSample[i][b];
    total += (*totals)[i];
  }
  for (double& m : s.mean) m /= total;
  const double meanTotal = total / double(samples);
  for (size_t b = 0; b < bins; ++b) {
    double sum = 0, sumSq = 0;
    for (size_t i = 0; i < samples; ++i) {
      const double d = perSample[i][b] - s.mean[b] * (*totals)[i];
      sum += d;
      sumSq += d * d;
    }
    const double var = (sumSq - sum * sum / double(samples)) / double(samples - 1);
    s.stdError[b] = std::sqrt(var / double(samples)) / meanTotal;
  }
  return s;
}

ResampledTarget sampleTarget(const Scene& scene, int samples,
                             std::function<bool(const Path&)> keep = {}) {
  ResampledTarget target;
  target.keep = std::move(keep);
  const int maxDepth = maxDepthOf(scene);
  const int blocks = kBlocks * kBlocks;
  std::vector<std::vector<double>> perSample(samples, std::vector<double>(blocks, 0.0));
  tbb::parallel_for(0, samples, [&](int i) {
    Rng rng(target.seed, uint64_t(i));
    IndependentSampler sampler(&rng);
    BidirectionalTracer tracer(scene, maxDepth);
    const Vec2f film = primarySampleFilmPoint(scene.camera(), sampler);
    if (target.keep) {
      tracer.visitStrategies(film, sampler, [&](const BidirectionalTracer::StrategyPath& sp) {
        if (!target.keep(Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t))) return;
        perSample[i][size_t(blockOf(sp.film))] += luminance(sp.unweighted) * sp.weight;
      });
      return;
    }
    std::vector<Splat> splats;
    tracer.sample(film, sampler, &splats);
    for (const Splat& s : splats) perSample[i][size_t(blockOf(s.film))] += luminance(s.value);
  });
  std::vector<double> totals;
  target.shares = ratioShares(perSample, &totals);
  double total = 0;
  for (double t : totals) target.cumulative.push_back(total += t);
  return target;
}

// An independent draw from the resampled measure: a sample by its total, rebuilt from its
// stream, then one of its strategies' paths by its share.
Path drawSeed(const Scene& scene, const ResampledTarget& target, Rng& rng) {
  const int maxDepth = maxDepthOf(scene);
  for (;;) {
    const double u = rng.nextDouble() * target.cumulative.back();
    const int i = int(std::upper_bound(target.cumulative.begin(), target.cumulative.end(), u) -
                      target.cumulative.begin());
    Rng sampleRng(target.seed, uint64_t(std::min(i, int(target.cumulative.size()) - 1)));
    IndependentSampler sampler(&sampleRng);
    BidirectionalTracer tracer(scene, maxDepth);
    std::vector<Path> paths;
    std::vector<double> run;
    tracer.visitStrategies(
        primarySampleFilmPoint(scene.camera(), sampler), sampler,
        [&](const BidirectionalTracer::StrategyPath& sp) {
          Path x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
          if (!x.contribution(scene, maxDepth).carriesLight()) return;
          if (target.keep && !target.keep(x)) return;
          paths.push_back(std::move(x));
          run.push_back((run.empty() ? 0 : run.back()) + luminance(sp.unweighted) * sp.weight);
        });
    if (paths.empty()) continue;
    const double v = rng.nextDouble() * run.back();
    const size_t k = size_t(std::upper_bound(run.begin(), run.end(), v) - run.begin());
    return paths[std::min(k, paths.size() - 1)];
  }
}

// The target's own BDPT estimate as the reference: its error is counted once, as the seeds'
// measure's (expectStationary adds target.shares.stdError), so that it carries none here.
Shares ownEstimate(const ResampledTarget& target) {
  Shares s;
  s.mean = target.shares.mean;
  s.stdError.assign(s.mean.size(), 0.0);
  return s;
}

Shares referenceShares() {
  Image ref;
  std::string error;
  if (!readExr(kShared + "/references/cornell-box-256.exr", &ref, &error))
    throw std::runtime_error(error);
  Shares s;
  s.mean.assign(kBlocks * kBlocks, 0.0);
  s.stdError.assign(kBlocks * kBlocks, 0.0);  // 4096 samples per pixel: negligible here
  double total = 0;
  for (int y = 0; y < ref.height; ++y) {
    for (int x = 0; x < ref.width; ++x) {
      double v = luminance(ref.at(x, y));
      s.mean[size_t(x * kBlocks / ref.width + kBlocks * (y * kBlocks / ref.height))] += v;
      total += v;
    }
  }
  for (double& v : s.mean) v /= total;
  return s;
}

// The bin whose mean share over independent chains (shares[chain][bin]) lies most standard
// errors from expected's, each bin's error being the chains' spread's, expected's own and
// `extraError`'s (the seeds' measure's, or empty), in quadrature.
struct WorstBin {
  int bin = -1;
  double z = 0;
};
WorstBin worstBin(const std::vector<std::vector<double>>& shares, const Shares& expected,
                  const std::vector<double>& extraError, const char* what) {
  WorstBin worst;
  for (size_t b = 0; b < expected.mean.size(); ++b) {
    std::vector<double> ofChains;
    for (const auto& s : shares) ofChains.push_back(s[b]);
    const MeanEstimate m = meanOfIndependent(ofChains);
    const double extra = extraError.empty() ? 0.0 : extraError[b];
    const double se = std::sqrt(m.standardError * m.standardError +
                                expected.stdError[b] * expected.stdError[b] + extra * extra);
    const double z = std::fabs(m.mean - expected.mean[b]) / se;
    if (getenv("SHARES_DEBUG"))
      std::printf("  %s %2zu: chains %.5f +- %.5f, expected %.5f +- %.5f\n", what, b, m.mean,
                  m.standardError, expected.mean[b], std::hypot(expected.stdError[b], extra));
    if (z > worst.z) worst = {int(b), z};
  }
  return worst;
}

// Runs `chains` production chains of one mutation alone, each from an independent seed, and
// tests their mean block shares against `expected`, whose standard error is added to the
// chains' and the seeds' measure's.
void expectStationary(const Scene& scene, const ResampledTarget& target, const Shares& expected,
                      MutationType type, int chains, int64_t mutations) {
  const int blocks = kBlocks * kBlocks;
  std::vector<std::string> seeds;
  Rng seedRng(123, uint64_t(type));
  for (int c = 0; c < chains; ++c) seeds.push_back(drawSeed(scene, target, seedRng).serialize());
  std::vector<std::vector<double>> shares(chains);
  std::vector<int64_t> proposed(chains, 0), accepted(chains, 0);
  tbb::parallel_for(0, chains, [&](int c) {
    ChainSpec spec;
    spec.algorithm = Algorithm::MLT;
    spec.chainIndex = uint32_t(c);
    spec.seed = 5;
    spec.maxDepth = maxDepthOf(scene);
    spec.budget = mutations;
    spec.flushInterval = mutations;
    spec.seedPath = seeds[c];
    MutationMix only{0, 0, 0, 0, 0, 0};
    double* weights[] = {&only.bidirectional,          &only.lensSubpath,
                         &only.lensPerturbation,       &only.causticPerturbation,
                         &only.multiChainPerturbation, &only.manifoldPerturbation};
    *weights[int(type)] = 1;
    spec.mutationMix = only;
    std::vector<double> block(blocks, 0.0);
    runMltChain(scene, spec, [&](ChainFlush&& f) {
      for (int y = 0; y < kFilm; ++y) {
        for (int x = 0; x < kFilm; ++x) {
          size_t i = size_t(y * kFilm + x) * 3;
          block[size_t(blockOf(Vec2f(x + 0.5f, y + 0.5f)))] +=
              luminance(Spectrum(f.splats[i], f.splats[i + 1], f.splats[i + 2]));
        }
      }
      for (const MutationTally& t : f.tallies) {
        if (t.name != mutationName(type)) continue;  // not the manifold walks' own tally
        proposed[c] += t.proposed;
        accepted[c] += t.accepted;
      }
      return true;
    });
    double total = 0;
    for (double v : block) total += v;
    for (double& v : block) v /= total;
    shares[c] = block;
  });
  const double threshold = normalQuantile(1 - kAlpha / (2 * blocks));
  const WorstBin worst = worstBin(shares, expected, target.shares.stdError, "block");
  int64_t p = 0, a = 0;
  for (int c = 0; c < chains; ++c) p += proposed[c], a += accepted[c];
  EXPECT_LE(worst.z, threshold) << mutationName(type) << ": block " << worst.bin << " is "
                                << worst.z << " standard errors off";
  EXPECT_GT(p, chains * mutations / 20) << mutationName(type) << " hardly ever applies";
  EXPECT_GT(a, p / 100) << mutationName(type) << " hardly ever moves the chain";
  std::printf(
      "%s: worst block %d at %.2f standard errors (bound %.2f); %lld proposals, %.1f%% "
      "accepted\n",
      mutationName(type), worst.bin, worst.z, threshold, (long long)p, p > 0 ? 100.0 * a / p : 0.0);
}

// Every mutation alone keeps the target, against a BDPT estimate of it (its error counted):
// scenes with specular surfaces, where all six apply.
void expectEveryMutationStationary(const Scene& scene) {
  const ResampledTarget target = sampleTarget(scene, 1 << 19);
  const Shares none = ownEstimate(target);
  for (MutationType t : {MutationType::Bidirectional, MutationType::LensSubpath,
                         MutationType::LensPerturbation, MutationType::CausticPerturbation,
                         MutationType::MultiChainPerturbation, MutationType::ManifoldPerturbation})
    expectStationary(scene, target, none, t, 480, 4000);
}

TEST(MltChain, StationaryInTheCornellBox) {
  auto scene = loadSmall(cornellBox());
  const ResampledTarget target = sampleTarget(*scene, 1 << 18);
  const Shares reference = referenceShares();
  for (MutationType t : {MutationType::Bidirectional, MutationType::LensSubpath,
                         MutationType::LensPerturbation, MutationType::CausticPerturbation})
    expectStationary(*scene, target, reference, t, 640, 3000);
}

TEST(MltChain, StationaryAroundTheGlassBall) {
  auto scene = loadSmall(glassBallScene());
  expectEveryMutationStationary(*scene);
}

// Under an image sky every mutation keeps the target where paths start on the environment: the
// reference is a BDPT estimate (its error counted), as around the glass ball.
TEST(MltChain, StationaryUnderAnImageSky) {
  auto scene = loadSmall(std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt");
  ASSERT_TRUE(scene->lights().environment());
  const ResampledTarget target = sampleTarget(*scene, 1 << 18);
  const Shares none = ownEstimate(target);
  // (Not the caustic perturbation: its paths here start on the sky, where it does not apply.)
  for (MutationType t :
       {MutationType::Bidirectional, MutationType::LensSubpath, MutationType::LensPerturbation})
    expectStationary(*scene, target, none, t, 480, 3000);
}

// The glass ball seen from close by, lit by its area light and a bright blue sky at once:
// paths that reach either light through the ball, and chains that switch between the two.
std::string glassBallUnderSky() {
  return writeGlassBallScene(
      "mlt_glass_ball_sky.xml", "0, 1.7, -1.4", "0, 0.7, 0",
      R"(<emitter type="constant"><rgb name="radiance" value="0.3 0.5 1.5"/></emitter>)");
}

TEST(MltChain, StationaryAroundTheGlassBallUnderSkyAndLight) {
  auto scene = loadSmall(glassBallUnderSky());
  ASSERT_TRUE(scene->lights().environment());
  expectEveryMutationStationary(*scene);
}

// The water caustic (../shared/scenes/water-caustic) on its own mesh, whose vertex normals are
// all vertical, as its reference was rendered (lax normals, 8 edges), with
// its light two hundred times wider and deeper (1 m by 0.8 m) so that BDPT's camera paths reach
// it through the water often enough for a reference of every path, L S D S E too
// (manifold_next_event_test.cpp): the manifold perturbation walks chains over a surface whose
// normals are not its geometry's, as nowhere around the glass ball. Its power is modest: the
// light seen directly holds 70% of the luminance, and the blocks under the water come from few
// chains each. With the generalized geometry term left out of the manifold perturbation's
// density, a block lies 4.7 standard errors off (bound 4.5); the mesh's normal derivative is
// zero here (see the next test), and manifold_walk_test.cpp's smooth patch tests it.
std::shared_ptr<Scene> waterUnderAWideLight() {
  SceneDescription desc = loadSmall(kShared + "/scenes/water-caustic/scene.xml")->description();
  desc.maxDepth = 8;
  desc.strictNormals = false;
  widenAreaLights(desc, 200.0f);
  return std::make_shared<Scene>(desc);
}

TEST(MltChain, StationaryOverTheWaterUnderAWideLight) {
  auto scene = waterUnderAWideLight();
  expectEveryMutationStationary(*scene);
}

// The manifold perturbation alone, on the paths it applies to: the target restricted to them
// (BDPT's strategies' paths that it applies to, by their MIS-weighted luminance), from which
// the chains start and which they must keep, without the light seen directly that holds most
// of the luminance above and leaves the blocks under the water few chains each. Measured at
// this size (480 chains of 8000 steps, 20 s): the worst block 2.25 standard errors off (bound
// 4.52), 1.1 with 1920 chains of 20000 steps; with the generalized geometry term left out of
// the perturbation's density, 16.6, where the test of every mutation above sees 4.7. The
// mesh's normal derivative left out changes nothing here, and cannot: every one of the
// surface's 54771 vertex normals in Mesh001.obj is (0, 1, 0), so its shading normal is vertical
// everywhere and turns nowhere (while its geometry tilts from it by 26 degrees at the median
// and 47 at the 90th percentile, by area); manifold_walk_test.cpp's smooth patch tests that term.
TEST(MltChain, ManifoldPerturbationKeepsItsOwnPathsOverTheWater) {
  auto scene = waterUnderAWideLight();
  const MutationContext context{*scene, maxDepthOf(*scene)};
  const ManifoldPerturbation manifold(context);
  const int samples = 1 << 19, chains = 480, steps = 8000;
  const ResampledTarget target =
      sampleTarget(*scene, samples, [&](const Path& x) { return manifold.appliesTo(x); });
  const Shares none = ownEstimate(target);
  expectStationary(*scene, target, none, MutationType::ManifoldPerturbation, chains, steps);
}

// --- The lens point ---------------------------------------------------------------------------
//
// Through a thin lens the camera vertex is a point of the lens, and the target distributes it
// as the luminance the paths through each part of the lens carry. The bidirectional and lens
// subpath mutations regrow it (a new uniform lens point); chains started from independent draws
// of the target keep its distribution over the lens at every step, and move it. Bins: four rings
// of equal area, each halved left and right, on tests/data/thin-lens (its lens in the plane
// z = 0 about the origin). The target's bin shares come from BDPT's strategies, each path's
// luminance by the lens point its camera subpath sampled.

constexpr int kLensBins = 8;

int lensBin(const Scene& scene, const Vec3f& p) {
  const float radius = scene.description().camera.lensRadius;
  const Vec3f o = (p - scene.camera().position()) / radius;
  const int ring = std::min(int(4 * (o.x * o.x + o.y * o.y)), 3);
  return 2 * ring + (o.x > 0 ? 1 : 0);
}

Shares lensShares(const Scene& scene, int samples) {
  const int maxDepth = maxDepthOf(scene);
  std::vector<std::vector<double>> perSample(samples, std::vector<double>(kLensBins, 0.0));
  tbb::parallel_for(0, samples, [&](int i) {
    Rng rng(78, uint64_t(i));
    IndependentSampler sampler(&rng);
    BidirectionalTracer tracer(scene, maxDepth);
    tracer.visitStrategies(primarySampleFilmPoint(scene.camera(), sampler), sampler,
                           [&](const BidirectionalTracer::StrategyPath& sp) {
                             perSample[i][size_t(lensBin(scene, sp.camera[0].p))] +=
                                 luminance(sp.unweighted) * sp.weight;
                           });
  });
  std::vector<double> totals;
  return ratioShares(perSample, &totals);
}

void expectLensPointStationary(const Scene& scene, const ResampledTarget& target,
                               const Shares& expected, MutationType type, int chains, int steps) {
  std::vector<std::vector<double>> shares(chains, std::vector<double>(kLensBins, 0.0));
  std::vector<int64_t> moved(chains, 0);
  Rng seedRng(321, uint64_t(type));
  std::vector<Path> seeds;
  for (int c = 0; c < chains; ++c) seeds.push_back(drawSeed(scene, target, seedRng));
  tbb::parallel_for(0, chains, [&](int c) {
    MutationMix only{0, 0, 0, 0, 0, 0};
    double* weights[] = {&only.bidirectional,          &only.lensSubpath,
                         &only.lensPerturbation,       &only.causticPerturbation,
                         &only.multiChainPerturbation, &only.manifoldPerturbation};
    *weights[int(type)] = 1;
    PathChain chain(scene, maxDepthOf(scene), only);
    SplatBuffer film(scene.camera().width(), scene.camera().height(),
                     PixelFilter::of(scene.description().camera));
    Rng rng(6, uint64_t(c));
    ASSERT_TRUE(chain.start(seeds[size_t(c)], rng));
    for (int i = 0; i < steps; ++i) {
      const Vec3f before = chain.current().vertices.back().p;
      chain.step(rng, film, 1.0f);
      const Vec3f after = chain.current().vertices.back().p;
      shares[c][size_t(lensBin(scene, after))] += 1.0 / steps;
      moved[c] += after.x != before.x || after.y != before.y;
    }
  });
  const double threshold = normalQuantile(1 - kAlpha / (2 * kLensBins));
  const WorstBin worst = worstBin(shares, expected, {}, "lens bin");
  int64_t movedTotal = 0;
  for (int64_t v : moved) movedTotal += v;
  const double movedShare = double(movedTotal) / (double(chains) * steps);
  EXPECT_LE(worst.z, threshold) << mutationName(type) << ": lens bin " << worst.bin << " is "
                                << worst.z << " standard errors off";
  // The new lens points must be taken (the bidirectional mutation renews the lens point in
  // about one proposal in ten and sees most of them fail in this scene: 2.8% of its steps).
  EXPECT_GT(movedShare, 0.01) << mutationName(type) << " hardly ever moves the lens point";
  std::printf(
      "%s through a thin lens: worst lens bin %d at %.2f standard errors (bound %.2f); "
      "the lens point moved on %.1f%% of steps\n",
      mutationName(type), worst.bin, worst.z, threshold, 100 * movedShare);
}

TEST(MltChain, LensPointStationaryThroughAThinLens) {
  auto scene = loadSmall(std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt");
  ASSERT_TRUE(scene->camera().hasLens());
  ASSERT_GT(scene->camera().forward().z, 0.999f);  // the lens in the plane z = 0, as lensBin has it
  const ResampledTarget target = sampleTarget(*scene, 1 << 17);
  const Shares expected = lensShares(*scene, 1 << 18);
  for (MutationType t : {MutationType::Bidirectional, MutationType::LensSubpath})
    expectLensPointStationary(*scene, target, expected, t, 400, 2000);
}

// --- Resume ----------------------------------------------------------------------------------

// Chain `index` of a few seeded in `scene`, run whole and resumed after its first flush; the
// spec, and the uninterrupted run's flushes.
std::vector<ChainFlush> expectChainResumes(const Scene& scene, const BootstrapResult& seeds,
                                           int index, ChainSpec* spec) {
  spec->algorithm = Algorithm::MLT;
  spec->chainIndex = uint32_t(index);
  spec->seed = 9;
  spec->maxDepth = maxDepthOf(scene);
  spec->budget = 3000;
  spec->flushInterval = 1000;
  spec->seedPath = seeds.seedPaths[size_t(index)];
  return expectResumesExactly(
      *spec, 0, [&](const ChainSpec& c, const FlushSink& sink) { runMltChain(scene, c, sink); });
}

TEST(MltChain, ResumedChainContinuesExactly) {
  auto scene = loadSmall(glassBallScene());
  ChainSpec spec;
  std::vector<ChainFlush> whole = expectChainResumes(*scene, bootstrapSeeds(scene, 4, 9), 2, &spec);
  ASSERT_EQ(whole.size(), 3u);
  ChainSpec corrupt = spec;
  corrupt.resumeState = "garbage";
  EXPECT_THROW(runMltChain(*scene, corrupt, [](ChainFlush&&) { return true; }), std::runtime_error);
  ChainSpec noSeed = spec;
  noSeed.seedPath.clear();
  EXPECT_THROW(runMltChain(*scene, noSeed, [](ChainFlush&&) { return true; }), std::runtime_error);
}

// A chain whose paths start at a point light (a light vertex without a shape) resumes from its
// state too.
TEST(MltChain, ResumedChainFromAPointLightContinuesExactly) {
  const std::string file = litBoxScene(
      "LightSource \"point\" \"rgb I\" [4 4 4] \"point from\" "
      "[0 2.5 1.5]\n");
  auto scene = loadSmall(file);
  ChainSpec spec;
  EXPECT_EQ(expectChainResumes(*scene, bootstrapSeeds(scene, 4, 9), 1, &spec).size(), 3u);
  std::filesystem::remove(file);
}

// A chain through a thin lens, whose states' camera vertices lie anywhere on the lens, resumes
// from its state too.
TEST(MltChain, ResumedChainThroughAThinLensContinuesExactly) {
  auto scene = loadSmall(std::string(FARM_TEST_DATA_DIR) + "/thin-lens/scene.pbrt");
  ChainSpec spec;
  EXPECT_EQ(expectChainResumes(*scene, bootstrapSeeds(scene, 4, 9), 1, &spec).size(), 3u);
}

// A chain under an image sky, whose states start on the environment (a vertex at infinity, its
// own kind in the state's bytes), resumes from its state too.
TEST(MltChain, ResumedChainUnderAnImageSkyContinuesExactly) {
  auto scene = loadSmall(std::string(FARM_TEST_DATA_DIR) + "/sky/scene.pbrt");
  const BootstrapResult seeds = bootstrapSeeds(scene, 16, 9);
  int index = -1;  // a seed from the sky
  for (size_t c = 0; c < seeds.seedPaths.size() && index < 0; ++c) {
    Path x;
    ASSERT_TRUE(x.deserialize(seeds.seedPaths[c], *scene));
    if (atInfinity(x[0])) index = int(c);
  }
  ASSERT_GE(index, 0);
  ChainSpec spec;
  EXPECT_EQ(expectChainResumes(*scene, seeds, index, &spec).size(), 3u);
}

// A pseudo-marginal chain through the smoke room's grid resumes exactly: its state keeps the
// estimate of f(x) that it accepted with (drawing a new one on resume would spend the RNG's
// numbers on it and part from the uninterrupted run).
TEST(MltChain, ResumedPseudoMarginalChainThroughSmokeContinuesExactly) {
  auto scene = loadSmall(std::string(FARM_TEST_DATA_DIR) + "/smoke-room/scene.xml");
  ASSERT_TRUE(scene->hasMedia());
  ChainSpec spec;
  spec.mediumSamples = 2;
  const std::vector<ChainFlush> whole =
      expectChainResumes(*scene, bootstrapSeeds(scene, 4, 9), 3, &spec);
  EXPECT_EQ(whole.size(), 3u);
}

}  // namespace
}  // namespace farm
