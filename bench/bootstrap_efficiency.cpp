// The bootstrap's efficiency on a scene: Z, its standard error, the candidates' relative
// variance v = N (stdError / Z)^2 and the time they took, so that v times the seconds per
// candidate (the relative variance of Z per second of bootstrap, lower is better) compares two
// ways of estimating Z at equal time. Used to choose which paths manifold next-event estimation
// takes from BDPT (docs/specular.md); run two builds one after the other on an idle machine.
//
//   farm_bootstrap_efficiency SCENE.xml [algorithm=mlt] [candidates=262144] [seed=1]
//       [max-depth=-1]
//
// The scene is read with lax shading normals at 128x128.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "common/mcmc/bootstrap.h"
#include "common/render/render_job.h"
#include "common/scene/scene.h"

using namespace farm;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE.xml [algorithm] [candidates] [seed] [max-depth]\n",
                 argv[0]);
    return 2;
  }
  Algorithm algorithm = Algorithm::MLT;
  if (argc > 2 && !parseAlgorithm(argv[2], &algorithm)) {
    std::fprintf(stderr, "unknown algorithm %s\n", argv[2]);
    return 2;
  }
  const int64_t n = argc > 3 ? std::atoll(argv[3]) : (1 << 18);
  const uint64_t seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1;
  const int maxDepth = argc > 5 ? std::atoi(argv[5]) : -1;
  RenderSettings settings;
  settings.width = settings.height = 128;
  settings.shadingNormals = ShadingNormals::Lax;
  const auto scene = loadScene(argv[1], settings);
  BootstrapCandidates c;
  const auto start = std::chrono::steady_clock::now();
  extendCandidates(candidateEvaluator(*scene, algorithm, maxDepth, seed), n, &c);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rel = c.mean > 0 ? c.stdError / c.mean : 0;
  std::printf(
      "Z %.6g +- %.3g (%.3f%%), relative variance %.3g, %lld candidates in %.2f s (%.0f/s), "
      "relative variance x seconds per candidate %.3g\n",
      c.mean, c.stdError, 100 * rel, rel * rel * double(n), (long long)n, seconds,
      double(n) / seconds, rel * rel * seconds);
  return 0;
}
