#pragma once
// Planning a job (common/plan/render_plan.h) and, for --algorithm auto --pilot, the pilot that
// ranks the plan's candidates (without --pilot the plan's first renders): each renders for a few
// seconds in this process, its chains in independent groups whose spread estimates its relative MSE
// without a reference (common/film/batch_means.h); with three or more candidates each one's error
// is also estimated from how its image differs from the others' (common/film/cross_estimate.h),
// which sees light it has not found and they have, and the larger estimate counts. The candidate
// whose estimate times its render time is least renders the job. Relative MSE falls as 1 / time for
// every algorithm here, so that product is what one second of the candidate would leave: a pilot of
// equal seconds each ranks them as the job would, up to the pilot's noise. The bootstrap's own time
// is left out of the product: in the job it is a few percent (common/mcmc/bootstrap_size.h), in a
// pilot of a second it can be most of it.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/plan/render_plan.h"
#include "common/render/render_settings.h"

namespace farm {

class Scene;

// The share of a job's time budget the pilot may take, its seconds per candidate without a
// budget (a job of counts), and its bounds: a candidate gets at most kPilotMaxSeconds, and a
// budget whose share would give each less than kPilotMinSeconds gets no pilot (the plan's
// first candidate renders, and the plan says why): under a second, the estimate mostly
// measures how fast a candidate covers the image.
constexpr double kPilotShare = 0.1;
constexpr double kPilotSecondsWithoutBudget = 1.0;
constexpr double kPilotMinSeconds = 1.0, kPilotMaxSeconds = 5.0;
// The pilot overrules the plan's first candidate only for one whose score is under the first's
// over this: a pilot's estimate at a few samples per pixel scatters by tens of percent and
// overrates what covers the image fastest (measured on veach-mis, where pilots of 0.2-2 s
// ranked pt, bdpt and pssmlt three ways, and bdpt led at 10, 30 and 100 s).
constexpr double kPilotMargin = 2.0;

// Seconds per candidate; 0: no pilot.
double pilotSecondsEach(const RenderSettings& settings, size_t candidates);

// Renders each candidate for `seconds` (its bootstrap included) and returns their figures,
// best score first; a candidate that fails (no light, cancelled) has a failure and sorts
// last. Stops early, returning what it has, when keepGoing returns false.
std::vector<PilotFigure> runPilot(std::shared_ptr<const Scene> scene,
                                  const RenderSettings& settings,
                                  const std::vector<Algorithm>& candidates, double seconds,
                                  const std::function<bool()>& keepGoing = {});

// --algorithm auto, where the plan picks bdpt and the job has a time budget: a pilot of
// kAllocationShare of the budget (at least kAllocationMinSeconds, at most kPilotMaxSeconds)
// renders the job's algorithm under another seed, and its chain groups' spread places the job's
// samples (PixelAllocation::byError). Measured on corpus scenes of both halves, bdpt's error
// fell where its error is uneven over the image and stayed where it is not; pt's hardly moved,
// so pt keeps uniform sampling (docs/corpus.md, "Per-pixel estimators and sample density").
constexpr double kAllocationShare = 0.1;
constexpr double kAllocationMinSeconds = 0.5;
constexpr uint64_t kAllocationSeedSalt = 0x6a09e667f3bcc909ull;
// Rng::seed adds the seed to the state of a stream that depends on the sample's index alone: the
// pilot's sample k and the job's run the same PCG stream, (seed ^ salt) - seed steps apart, odd
// (an odd salt flips the lowest bit) and so never zero.
static_assert(kAllocationSeedSalt % 2 == 1, "the salt must be odd");

// The allocation pilot's seconds for these settings; 0: none.
double allocationPilotSeconds(const RenderSettings& settings);

// The allocation pilot's samples, kept for the job's image (coordinator/job.cpp,
// SplatAggregator::addPrior). They are the job's algorithm sampled uniformly over the film under
// a seed of their own, and so an unbiased estimate of the image the job's allocated samples
// estimate (each allocated splat carries 1 / its density, common/film/pixel_allocation.h): the
// pooled (pilot's splats + job's splats) / (pilot's samples + job's samples) is unbiased too,
// and the pilot's share of the budget is not lost.
struct PilotSamples {
  std::vector<double> sums;                   // the film, width*height*3, every group's
  std::vector<std::vector<float>> groupSums;  // each of the pilot's error groups' film
  std::vector<int64_t> groupWork;             // samples, per group
  int64_t work = 0;                           // samples, all groups
  uint64_t seed = 0;                          // the pilot's (the job's ^ kAllocationSeedSalt)
};

// The relative MSE of n_p uniform samples pooled with n_j allocated ones, (S_p + S_j) / n,
// over that of the n_j alone, for an allocation of concentration K
// (PixelAllocation::concentration): a pixel's error per uniform sample e becomes
// e (n_p + n_j / r) / n^2 against e / (n_j r), r its relative density, and over the film with
// e ~ r^2 their ratio is n_j (n_p K + n_j) / n^2. Under 1 where the allocation is mild; over it
// where the allocation gathers the samples, K above about 2 + n_p / n_j (light through glass,
// where the allocated samples are several times better spent than uniform ones).
double pooledErrorRatio(double pilotSamples, double jobSamples, double concentration);

// Renders settings.algorithm (pt or bdpt) for `seconds` under a seed of its own and returns the
// allocation its error asks for, with *why saying what it did; nullptr (and *why saying so)
// when the pilot failed. The pilot renders twice the job's error groups, which all place the
// samples; with `samples`, the second half goes there for the job's image when
// pooledErrorRatio, at the concentration of the first half's allocation, is under 1
// (otherwise, and on failure, it is left empty).
std::shared_ptr<const PixelAllocation> allocationPilot(std::shared_ptr<const Scene> scene,
                                                       RenderSettings settings, double seconds,
                                                       const std::function<bool()>& keepGoing,
                                                       std::string* why,
                                                       PilotSamples* samples = nullptr);

// What the pilot's figures (best score first) pick: the plan's first candidate, unless it
// failed or another's score is under its own over kPilotMargin.
Algorithm pilotPick(Algorithm first, const std::vector<PilotFigure>& figures);

// The job's plan, applied to *settings: with settings->autoAlgorithm the algorithm the plan
// (and with settings->pilot its pilot, where it has more than one candidate) picks; unless
// settings->ignorePlan, mlt's mutation mix with the parts the scene does not need at zero weight.
// With `pilotSamples`, an allocation pilot's samples go there for the job's image (work 0: none;
// the ranking pilot's are not kept, as they share the job's seed).
RenderPlan planJob(std::shared_ptr<const Scene> scene, RenderSettings* settings,
                   const std::function<bool()>& keepGoing = {},
                   PilotSamples* pilotSamples = nullptr);

}  // namespace farm
