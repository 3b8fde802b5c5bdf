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
#include <cstdint>

#include "common/chain/algorithm.h"

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

}  // namespace farm
