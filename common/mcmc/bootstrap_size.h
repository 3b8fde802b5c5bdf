#pragma once
// How many candidates a job's bootstrap draws (Veach 1997, 11.3), sized to the job rather than to
// the film. Two demands fix the count:
//
//  - time: the candidates should cost at most kBootstrapShare of the job, the chains' work
//    included. A candidate's cost, in units of the algorithm's own work (one mutation, or one of
//    ERPT's samples), is the table in bootstrap_size.cpp, measured on the shared scenes at equal
//    thread counts; so the bound holds where the coordinator has as many threads as the farm
//    (a farm with more runs the chains faster and the share grows).
//  - error: Z scales the whole image, so its error does not average away over pixels. Its
//    relative standard error sqrt(v / N) (v: the candidates' relative variance Var(I) / Z^2) is
//    kept within a third of the relative error of an average pixel of the finished job, modelled
//    as 1 / sqrt(M) at M units of work per pixel (one independent splat each; correlated chains
//    do worse, BDPT's many strategies and expected-value splatting better). Then Z adds about a
//    ninth to an average pixel's relative variance: N >= 9 v M. With a reference, the report
//    gives the share of the relative MSE that Z's error alone makes, measured.
//
// The count is the larger of the two, within [the job's pilot, kBootstrapMaxCandidates]: Z's
// error wins over the time share where both cannot hold (the report shows both). It depends only
// on the job and on the pilot's candidates, so the same job and seed bootstrap the same on every
// host.
//
// The pilot sizes the bootstrap and takes no part in it: Z and the seeds come from candidates
// drawn after it, whose count it fixed. A count chosen by the values it then averages biases the
// average: where light comes in rare bright candidates, a pilot that met one measures a large
// variance and asks for many more, which dilute it, and one that met none stops early, low
// (mlt's images of a glass ball came out dark on average: docs/specular.md). Given the count,
// the candidates drawn after the pilot average to Z whatever it was.
#include <cstdint>
#include <functional>

#include "common/chain/algorithm.h"
#include "common/mcmc/bootstrap.h"

namespace farm {

constexpr double kBootstrapShare = 0.05;
// The first candidates, whose relative variance sizes the rest (doubled until kPilotLight of them
// carry light, so that a scene where light is rare still gets a variance to go on): as many as the
// time share allows, within [kBootstrapPilotFloor, kBootstrapPilot]. Below the floor the
// variance, which sizes Z's error, is too rough to go on (n near-Gaussian values give it within
// sqrt(2 / n), 4.4% at 1024; candidates' heavy tails do worse); so jobs too small to afford the
// floor (mlt: under about 1.2 million mutations, 19 per pixel at 256x256) spend more than the share
// on it.
constexpr int64_t kBootstrapPilot = int64_t(1) << 12;
constexpr int64_t kBootstrapPilotFloor = int64_t(1) << 10;
constexpr int64_t kBootstrapPilotLight = 64;
constexpr int64_t kBootstrapPilotMax = int64_t(1) << 20;  // and no further: light is that rare
// 64 MiB of contributions; Z's error at this count is far below any job's noise.
constexpr int64_t kBootstrapMaxCandidates = int64_t(1) << 23;

// A candidate's cost in units of the algorithm's work (0 for algorithms without a bootstrap).
double bootstrapCandidateCost(Algorithm algorithm);

struct BootstrapSize {
  int64_t candidates = 0;
  int64_t forTime = 0;   // the count the time share allows
  int64_t forError = 0;  // the count Z's error asks for
};

// The pilot's count for a job of plannedWork mutations or samples (0: unknown, a time budget).
int64_t bootstrapPilot(Algorithm algorithm, int64_t plannedWork);

// plannedWork: the job's mutations or samples (> 0); pixels: the film's; relativeVariance: the
// pilot's Var(I) / mean(I)^2. The count is never below the job's pilot.
BootstrapSize bootstrapSize(Algorithm algorithm, int64_t plannedWork, int64_t pixels,
                            double relativeVariance);

// A job's bootstrap candidates: the job's settings say how many.
struct BootstrapRequest {
  Algorithm algorithm = Algorithm::PSSMLT;
  int64_t fixedCount = 0;        // > 0: exactly this many, no pilot
  int64_t plannedWork = 0;       // mutations or samples; <= 0: a time budget or unknown
  int64_t pixels = 0;            // the film's
  double timeBudgetSeconds = 0;  // > 0 with plannedWork <= 0: kBootstrapShare of it
};
struct SizedCandidates {
  BootstrapCandidates candidates;  // Z's and the seeds' (stream indices from their firstIndex)
  int64_t pilot = 0;               // the pilot's count, stream indices 0 .. pilot - 1
  BootstrapSize size;              // what sized them (0: not asked)
};

// Draws the candidates `request` asks for: a fixed count from index 0; otherwise the pilot
// (doubled until kBootstrapPilotLight of it carry light), then as many fresh candidates as the
// pilot's variance and the job ask for (bootstrapSize, at least the pilot's count), or, on a time
// budget, as many as kBootstrapShare of it allows at the rate measured. False when cancelled
// through `progress` (the fraction done of each round of drawing).
bool drawSizedCandidates(const CandidateEvaluator& evaluate, const BootstrapRequest& request,
                         SizedCandidates* out, const std::function<bool(double)>& progress = {});

}  // namespace farm
