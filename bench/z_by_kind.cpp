// Path-space MLT's Z (the bootstrap's estimate: BDPT's strategies, with manifold next-event
// estimation in place of those it covers) on a scene with specular interfaces at an index near 1,
// against Z of the same scene without them (BDPT alone), split by the kind of path.
//
// Near index 1 an interface neither bends nor reflects (to about 1e-4), so the two Zs must agree,
// and so must each kind of path: a path of the scene without the interfaces is given the kind it
// has in the scene with them by counting the specular surfaces each of its segments crosses there
// (L, then S per crossing and D per vertex, then E). A kind the first scene leaves at zero and the
// second does not is one no strategy there reaches in practice. This found the 0.8% of the water
// caustic's Z at index 1.0001 that neither BDPT (under its light of a few millimetres) nor manifold
// next-event estimation (chains of at most two vertices, paths of at most 10 edges) reached; see
// docs/specular.md.
//
//   farm_z_by_kind WET.xml DRY.xml [samples=262144] [max-depth=-1] [rows=30]
//
// Both scenes are read with lax shading normals at 128x128. Grazing rays (within a degree of the
// surface) are reflected wholly at 1.0001, so the kinds seen through several crossings differ a
// little between the two scenes; their sum does not.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "common/mcmc/manifold_next_event.h"
#include "common/mcmc/primary_sample_integrand.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"
#include "common/transport/bidirectional.h"
#include "common/transport/seen_emission.h"

using namespace farm;

namespace {

// Per kind of path, the sum over samples of what each sample gave it and of its square.
struct Tally {
  double sum = 0, sumSq = 0;
};
using Tallies = std::map<std::string, Tally>;

struct Sums {
  Tallies bdpt, manifold, without;
};

void fold(Tallies* into, const std::map<std::string, double>& sample) {
  for (const auto& [kind, value] : sample) {
    (*into)[kind].sum += value;
    (*into)[kind].sumSq += value * value;
  }
}

// The specular surfaces of `with` that the segment a -> b crosses.
int crossings(const Scene& with, const Vec3f& a, const Vec3f& b) {
  constexpr float kStep = 1e-4f;
  int count = 0;
  Vec3f o = a;
  for (int guard = 0; guard < 64; ++guard) {
    const Vec3f d = b - o;
    const float len = length(d);
    if (len < 3 * kStep) break;
    Ray r;
    r.d = d / len;
    r.o = o + r.d * kStep;
    r.tMax = len - 2 * kStep;
    SurfaceHit hit;
    if (!with.intersect(r, &hit)) break;
    if (with.bsdfOf(hit.shape).isDelta()) ++count;
    o = hit.p;
  }
  return count;
}

std::string kindIn(const Scene& scene, const Path& x) {
  std::string kind;
  const int n = int(x.vertices.size());
  for (int k = 0; k < n; ++k)
    kind += k == 0 ? 'L' : k == n - 1 ? 'E' : x.isSpecular(scene, k) ? 'S' : 'D';
  return kind;
}

// x's kind had its segments crossed the specular surfaces of `with`.
std::string kindWith(const Scene& with, const Path& x) {
  std::string kind = "L";
  for (size_t k = 0; k + 1 < x.vertices.size(); ++k) {
    if (k > 0) kind += 'D';
    kind += std::string(size_t(crossings(with, x.vertices[k].p, x.vertices[k + 1].p)), 'S');
  }
  return kind + 'E';
}

// BDPT's strategies of candidate i as path-space MLT's bootstrap takes them; `covered` says
// which paths another estimator takes instead.
template <typename Visit, typename Covered>
void bdptPaths(const Scene& scene, int maxDepth, Sampler& sampler, const Covered& covered,
               const Visit& visit) {
  BidirectionalTracer tracer(scene, maxDepth);
  tracer.visitStrategies(primarySampleFilmPoint(scene.camera(), sampler), sampler,
                         [&](const BidirectionalTracer::StrategyPath& sp) {
                           const double share = luminance(sp.unweighted) * sp.weight;
                           if (!(share > 0) || !std::isfinite(share)) return;
                           Path x = Path::fromSubpaths(sp.light, sp.s, sp.camera, sp.t);
                           if (SeenEmission::separates(scene) && x.isSeenEmission(scene)) return;
                           if (covered(x)) return;
                           visit(x, share);
                         });
}

double meanOf(const Tally& t, double n) {
  return t.sum / n;
}
double errorOf(const Tally& t, double n) {
  const double m = t.sum / n;
  return std::sqrt(std::max(0.0, t.sumSq / n - m * m) / n);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s WET.xml DRY.xml [samples] [max-depth] [rows]\n", argv[0]);
    return 2;
  }
  const int64_t samples = argc > 3 ? std::atoll(argv[3]) : (1 << 18);
  const int maxDepth = argc > 4 ? std::atoi(argv[4]) : -1;
  const size_t rows = argc > 5 ? size_t(std::atoi(argv[5])) : 30;
  RenderSettings settings;
  settings.width = settings.height = 128;
  settings.shadingNormals = ShadingNormals::Lax;
  const auto wet = loadScene(argv[1], settings);
  const auto dry = loadScene(argv[2], settings);
  tbb::enumerable_thread_specific<Sums> perThread;
  std::vector<double> wetZ(static_cast<size_t>(samples)), dryZ(static_cast<size_t>(samples));
  tbb::parallel_for(int64_t(0), samples, [&](int64_t i) {
    Sums& sums = perThread.local();
    std::map<std::string, double> bdpt, manifold, without;
    {
      Rng rng(7, uint64_t(i));
      IndependentSampler sampler(&rng);
      const ManifoldNextEvent estimator(*wet, maxDepth);
      const bool active = estimator.active();
      bdptPaths(
          *wet, maxDepth, sampler, [&](const Path& x) { return active && estimator.covers(x); },
          [&](const Path& x, double share) { bdpt[kindIn(*wet, x)] += share; });
      estimator.sample(sampler,
                       [&](const Path& x, double value) { manifold[kindIn(*wet, x)] += value; });
    }
    {
      Rng rng(8, uint64_t(i));
      IndependentSampler sampler(&rng);
      bdptPaths(
          *dry, maxDepth, sampler, [](const Path&) { return false; },
          [&](const Path& x, double share) { without[kindWith(*wet, x)] += share; });
    }
    for (const auto& [k, v] : bdpt) wetZ[size_t(i)] += v;
    for (const auto& [k, v] : manifold) wetZ[size_t(i)] += v;
    for (const auto& [k, v] : without) dryZ[size_t(i)] += v;
    fold(&sums.bdpt, bdpt);
    fold(&sums.manifold, manifold);
    fold(&sums.without, without);
  });
  Sums total;
  for (const Sums& s : perThread) {
    for (const auto& [k, t] : s.bdpt) total.bdpt[k].sum += t.sum, total.bdpt[k].sumSq += t.sumSq;
    for (const auto& [k, t] : s.manifold)
      total.manifold[k].sum += t.sum, total.manifold[k].sumSq += t.sumSq;
    for (const auto& [k, t] : s.without)
      total.without[k].sum += t.sum, total.without[k].sumSq += t.sumSq;
  }
  const double n = double(samples);
  auto zOf = [&](const std::vector<double>& z) {
    Tally t;
    for (double v : z) t.sum += v, t.sumSq += v * v;
    return t;
  };
  const Tally w = zOf(wetZ), d = zOf(dryZ);
  Tally wetBdpt, wetManifold;
  for (const auto& [k, t] : total.bdpt) wetBdpt.sum += t.sum;
  for (const auto& [k, t] : total.manifold) wetManifold.sum += t.sum;
  std::printf("%lld samples, max depth %d\n", (long long)samples, maxDepth);
  std::printf("Z with the interfaces    %.6g +- %.3g (BDPT %.6g, manifold next event %.6g)\n",
              meanOf(w, n), errorOf(w, n), meanOf(wetBdpt, n), meanOf(wetManifold, n));
  std::printf("Z without them           %.6g +- %.3g\n", meanOf(d, n), errorOf(d, n));
  std::printf("difference               %+.3f%% +- %.3f%%\n\n",
              100 * (meanOf(w, n) / meanOf(d, n) - 1),
              100 * std::hypot(errorOf(w, n), errorOf(d, n)) / meanOf(d, n));
  std::map<std::string, int> kinds;
  for (const Tallies* t : {&total.bdpt, &total.manifold, &total.without})
    for (const auto& [k, v] : *t) kinds[k] = 1;
  std::vector<std::pair<double, std::string>> order;
  for (const auto& [k, one] : kinds)
    order.push_back(
        {std::fabs(total.bdpt[k].sum + total.manifold[k].sum - total.without[k].sum), k});
  std::sort(order.rbegin(), order.rend());
  std::printf("%-18s %10s %10s %10s %10s %9s\n", "kind (with them)", "BDPT", "manifold", "without",
              "difference", "its error");
  for (size_t r = 0; r < order.size() && r < rows; ++r) {
    const std::string& k = order[r].second;
    const Tally &b = total.bdpt[k], &m = total.manifold[k], &o = total.without[k];
    const double error = std::sqrt(errorOf(b, n) * errorOf(b, n) + errorOf(m, n) * errorOf(m, n) +
                                   errorOf(o, n) * errorOf(o, n));
    std::printf("%-18s %10.4g %10.4g %10.4g %+10.4g %9.3g\n", k.c_str(), meanOf(b, n), meanOf(m, n),
                meanOf(o, n), meanOf(b, n) + meanOf(m, n) - meanOf(o, n), error);
  }
  return 0;
}
