#include "proto/convert.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "proto/sha256.h"

namespace farm {

namespace {
struct AlgorithmPair {
  Algorithm algorithm;
  v1::Algorithm wire;
};
constexpr AlgorithmPair kAlgorithms[] = {
    {Algorithm::PathTracing, v1::PT}, {Algorithm::Bidirectional, v1::BDPT},
    {Algorithm::PSSMLT, v1::PSSMLT},  {Algorithm::PSSMLTOverPT, v1::PSSMLT_PT},
    {Algorithm::MMLT, v1::MMLT},      {Algorithm::MLT, v1::MLT},
    {Algorithm::ERPT, v1::ERPT},
};
void toProto(const MutationMix& mix, v1::MutationMix* m) {
  m->set_bidirectional(mix.bidirectional);
  m->set_lens_subpath(mix.lensSubpath);
  m->set_lens_perturbation(mix.lensPerturbation);
  m->set_caustic_perturbation(mix.causticPerturbation);
  m->set_multi_chain_perturbation(mix.multiChainPerturbation);
  m->set_manifold_perturbation(mix.manifoldPerturbation);
}

// An absent mix (all zero) is the default one; any other must be usable.
bool fromProto(const v1::MutationMix& m, MutationMix* out, std::string* error) {
  MutationMix mix;
  if (m.bidirectional() != 0 || m.lens_subpath() != 0 || m.lens_perturbation() != 0 ||
      m.caustic_perturbation() != 0 || m.multi_chain_perturbation() != 0 ||
      m.manifold_perturbation() != 0) {
    mix.bidirectional = m.bidirectional();
    mix.lensSubpath = m.lens_subpath();
    mix.lensPerturbation = m.lens_perturbation();
    mix.causticPerturbation = m.caustic_perturbation();
    mix.multiChainPerturbation = m.multi_chain_perturbation();
    mix.manifoldPerturbation = m.manifold_perturbation();
  }
  std::string problem = validateMutationMix(mix);
  if (!problem.empty()) {
    *error = problem;
    return false;
  }
  *out = mix;
  return true;
}

// A pixel allocation's byte form (common/film/pixel_allocation.h), checked whole.
bool decodeAllocation(const std::string& bytes, std::shared_ptr<const PixelAllocation>* out,
                      std::string* error) {
  try {
    *out = std::make_shared<const PixelAllocation>(PixelAllocation::decode(bytes));
    return true;
  } catch (const std::invalid_argument& e) {
    *error = e.what();
    return false;
  }
}
}  // namespace

v1::Algorithm toProto(Algorithm algorithm) {
  for (const AlgorithmPair& p : kAlgorithms) {
    if (p.algorithm == algorithm) return p.wire;
  }
  return v1::ALGORITHM_UNSPECIFIED;
}

bool fromProto(v1::Algorithm algorithm, Algorithm* out, std::string* error) {
  for (const AlgorithmPair& p : kAlgorithms) {
    if (p.wire == algorithm) {
      *out = p.algorithm;
      return true;
    }
  }
  *error = "algorithm is unspecified or unknown (value " + std::to_string(int(algorithm)) +
           "); expected " + algorithmList();
  return false;
}

v1::RenderSettings toProto(const RenderSettings& settings, WithAllocation allocation) {
  v1::RenderSettings m;
  m.set_algorithm(toProto(settings.algorithm));
  m.set_width(settings.width);
  m.set_height(settings.height);
  m.set_samples_per_pixel(settings.samplesPerPixel);
  m.set_mutations_per_pixel(settings.mutationsPerPixel);
  m.set_time_budget_seconds(settings.timeBudgetSeconds);
  m.set_seed(settings.seed);
  m.set_max_depth(settings.maxDepth);
  m.set_bootstrap_samples(settings.bootstrapSamples);
  m.set_num_chains(settings.numChains);
  m.set_large_step_probability(settings.largeStepProbability);
  toProto(settings.mutationMix, m.mutable_mutation_mix());
  m.set_erpt_chains(settings.erptChains);
  m.set_erpt_length(settings.erptLength);
  m.set_flush_interval(settings.flushInterval);
  m.set_medium_samples(settings.mediumSamples);
  m.set_medium_march_steps(settings.mediumMarchSteps);
  m.set_until_error(settings.untilError);
  m.set_error_groups(settings.errorGroups);
  m.set_auto_algorithm(settings.autoAlgorithm);
  m.set_pilot(settings.pilot);
  m.set_combine_large_steps(settings.combineLargeSteps);
  m.set_ignore_plan(settings.ignorePlan);
  if (settings.pixelAllocation && allocation == WithAllocation::kIncluded)
    m.set_pixel_allocation(settings.pixelAllocation->encode());
  m.set_shading_normals(
      settings.shadingNormals == ShadingNormals::Strict ? v1::SHADING_NORMALS_STRICT
      : settings.shadingNormals == ShadingNormals::Lax  ? v1::SHADING_NORMALS_LAX
                                                        : v1::SHADING_NORMALS_SCENE);
  return m;
}

bool fromProto(const v1::RenderSettings& m, RenderSettings* out, std::string* error) {
  RenderSettings s;
  if (!fromProto(m.algorithm(), &s.algorithm, error)) return false;
  s.width = m.width();
  s.height = m.height();
  s.samplesPerPixel = m.samples_per_pixel();
  s.mutationsPerPixel = m.mutations_per_pixel();
  s.timeBudgetSeconds = m.time_budget_seconds();
  s.seed = m.seed();
  s.maxDepth = m.max_depth();
  s.bootstrapSamples = m.bootstrap_samples();
  s.numChains = m.num_chains();
  s.largeStepProbability = m.large_step_probability();
  if (!fromProto(m.mutation_mix(), &s.mutationMix, error)) return false;
  if (m.erpt_chains() != 0) s.erptChains = m.erpt_chains();
  if (m.erpt_length() != 0) s.erptLength = m.erpt_length();
  s.flushInterval = m.flush_interval();
  if (m.medium_samples() != 0) s.mediumSamples = m.medium_samples();
  s.mediumMarchSteps = m.medium_march_steps();
  s.untilError = m.until_error();
  s.errorGroups = m.error_groups();
  s.autoAlgorithm = m.auto_algorithm();
  s.pilot = m.pilot();
  s.combineLargeSteps = m.combine_large_steps();
  s.ignorePlan = m.ignore_plan();
  if (!m.pixel_allocation().empty() &&
      !decodeAllocation(m.pixel_allocation(), &s.pixelAllocation, error)) {
    return false;
  }
  switch (m.shading_normals()) {
    case v1::SHADING_NORMALS_SCENE:
      s.shadingNormals = ShadingNormals::Scene;
      break;
    case v1::SHADING_NORMALS_STRICT:
      s.shadingNormals = ShadingNormals::Strict;
      break;
    case v1::SHADING_NORMALS_LAX:
      s.shadingNormals = ShadingNormals::Lax;
      break;
    default:
      *error = "unknown shading-normal convention " + std::to_string(int(m.shading_normals()));
      return false;
  }
  *out = s;
  return true;
}

v1::ChainSpec toProto(const ChainSpec& spec) {
  v1::ChainSpec m;
  m.set_job_id(spec.jobId);
  m.set_chain_index(spec.chainIndex);
  m.set_algorithm(toProto(spec.algorithm));
  m.set_seed(spec.seed);
  m.set_max_depth(spec.maxDepth);
  m.set_large_step_probability(spec.largeStepProbability);
  m.set_first_sample(spec.firstSample);
  m.mutable_seed_sample()->Assign(spec.seedSample.begin(), spec.seedSample.end());
  m.set_seed_contribution(spec.seedContribution);
  m.set_budget(spec.budget);
  m.set_flush_interval(spec.flushInterval);
  m.set_resume_state(spec.resumeState);
  m.set_resume_mutations(spec.resumeMutations);
  m.set_resume_flush_index(spec.resumeFlushIndex);
  m.set_seed_path(spec.seedPath);
  toProto(spec.mutationMix, m.mutable_mutation_mix());
  m.set_tile_x(spec.tileX);
  m.set_tile_y(spec.tileY);
  m.set_tile_width(spec.tileWidth);
  m.set_tile_height(spec.tileHeight);
  m.set_erpt_chains(spec.erptChains);
  m.set_erpt_length(spec.erptLength);
  m.set_erpt_deposit(spec.erptDeposit);
  m.set_medium_samples(spec.mediumSamples);
  m.set_medium_march_steps(spec.mediumMarchSteps);
  m.set_error_group(spec.errorGroup);
  m.set_seen_emission_every(spec.seenEmissionEvery);
  m.set_seen_emission_scale(spec.seenEmissionScale);
  m.set_large_step_mis(spec.largeStepMis);
  if (spec.pixelAllocation) m.set_pixel_allocation_hash(pixelAllocationHash(spec.pixelAllocation));
  return m;
}

bool fromProto(const v1::ChainSpec& m, ChainSpec* out, std::string* error,
               const AllocationLookup& lookup) {
  ChainSpec s;
  if (!fromProto(m.algorithm(), &s.algorithm, error)) return false;
  s.jobId = m.job_id();
  s.chainIndex = m.chain_index();
  s.seed = m.seed();
  s.maxDepth = m.max_depth();
  s.largeStepProbability = m.large_step_probability();
  s.firstSample = m.first_sample();
  s.seedSample.assign(m.seed_sample().begin(), m.seed_sample().end());
  s.seedContribution = m.seed_contribution();
  s.budget = m.budget();
  s.flushInterval = m.flush_interval();
  s.resumeState = m.resume_state();
  s.resumeMutations = m.resume_mutations();
  s.resumeFlushIndex = m.resume_flush_index();
  s.seedPath = m.seed_path();
  if (!fromProto(m.mutation_mix(), &s.mutationMix, error)) return false;
  s.tileX = m.tile_x();
  s.tileY = m.tile_y();
  s.tileWidth = m.tile_width();
  s.tileHeight = m.tile_height();
  s.erptChains = m.erpt_chains();
  s.erptLength = m.erpt_length();
  s.erptDeposit = m.erpt_deposit();
  s.mediumSamples = m.medium_samples();
  s.mediumMarchSteps = m.medium_march_steps();
  s.errorGroup = m.error_group();
  s.seenEmissionEvery = m.seen_emission_every();
  s.seenEmissionScale = m.seen_emission_scale();
  s.largeStepMis = m.large_step_mis();
  if (!std::isfinite(s.largeStepMis) || s.largeStepMis < 0) {
    *error = "chain " + std::to_string(s.chainIndex) + " has a bad large-step weight " +
             std::to_string(s.largeStepMis) + " (must be finite and >= 0)";
    return false;
  }
  if (!m.pixel_allocation().empty() || !m.pixel_allocation_hash().empty()) {
    const std::string chain = "chain " + std::to_string(s.chainIndex);
    if (s.algorithm != Algorithm::PathTracing && s.algorithm != Algorithm::Bidirectional) {
      *error = chain + " of " + algorithmName(s.algorithm) +
               " has a pixel allocation (only pt and bdpt take one)";
      return false;
    }
    if (!m.pixel_allocation().empty()) {  // a plan record of protocol 7 or before
      if (!decodeAllocation(m.pixel_allocation(), &s.pixelAllocation, error)) {
        *error = chain + ": " + *error;
        return false;
      }
    } else {
      if (lookup) s.pixelAllocation = lookup(m.pixel_allocation_hash());
      if (!s.pixelAllocation) {
        *error = chain + " names pixel allocation " + m.pixel_allocation_hash().substr(0, 64) +
                 ", which did not come with it";
        return false;
      }
    }
  }
  if (s.seenEmissionEvery < 0 || !std::isfinite(s.seenEmissionScale) || s.seenEmissionScale < 0) {
    *error = "chain " + std::to_string(s.chainIndex) + " has a bad seen-emission sampling (every " +
             std::to_string(s.seenEmissionEvery) + ", scale " +
             std::to_string(s.seenEmissionScale) + ")";
    return false;
  }
  if (s.flushInterval <= 0) {
    *error = "chain " + std::to_string(s.chainIndex) + " has flush interval " +
             std::to_string(s.flushInterval) + " (must be > 0)";
    return false;
  }
  *out = s;
  return true;
}

std::string pixelAllocationHash(const std::shared_ptr<const PixelAllocation>& allocation) {
  // A weak pointer keeps the remembered allocation's address from being reused by another while
  // the hash is kept: it is compared only while the allocation lives.
  thread_local std::weak_ptr<const PixelAllocation> last;
  thread_local std::string lastHash;
  if (!allocation) return {};
  if (const auto held = last.lock(); held && held == allocation) return lastHash;
  lastHash = sha256Hex(allocation->encode());
  last = allocation;
  return lastHash;
}

bool decodePixelAllocation(const std::string& bytes, const std::string& hash,
                           std::shared_ptr<const PixelAllocation>* out, std::string* error) {
  if (sha256Hex(bytes) != hash) {
    *error = "pixel allocation bytes that are not " + hash.substr(0, 64);
    return false;
  }
  return decodeAllocation(bytes, out, error);
}

v1::JobPhase toProto(JobPhase phase) {
  switch (phase) {
    case JobPhase::kSubmitted:
      return v1::SUBMITTED;
    case JobPhase::kLoadingScene:
      return v1::LOADING_SCENE;
    case JobPhase::kBootstrapping:
      return v1::BOOTSTRAPPING;
    case JobPhase::kRendering:
      return v1::RENDERING;
    case JobPhase::kFinishing:
      return v1::FINISHING;
    case JobPhase::kDone:
      return v1::DONE;
    case JobPhase::kFailed:
      return v1::FAILED;
    case JobPhase::kCancelled:
      return v1::CANCELLED;
  }
  return v1::PHASE_UNSPECIFIED;
}

JobPhase fromProto(v1::JobPhase phase) {
  switch (phase) {
    case v1::LOADING_SCENE:
      return JobPhase::kLoadingScene;
    case v1::BOOTSTRAPPING:
      return JobPhase::kBootstrapping;
    case v1::RENDERING:
      return JobPhase::kRendering;
    case v1::FINISHING:
      return JobPhase::kFinishing;
    case v1::DONE:
      return JobPhase::kDone;
    case v1::FAILED:
      return JobPhase::kFailed;
    case v1::CANCELLED:
      return JobPhase::kCancelled;
    default:
      return JobPhase::kSubmitted;
  }
}

void toProto(const ChainFlush& f, uint64_t epoch, v1::FlushEntry* e) {
  e->set_chain_index(f.chainIndex);
  e->set_flush_index(f.flushIndex);
  e->set_epoch(epoch);
  e->set_mutations(f.mutations);
  e->set_rejected_nan(f.rejected.nan);
  e->set_rejected_infinite(f.rejected.infinite);
  e->set_rejected_negative(f.rejected.negative);
  e->set_rays(f.rays);
  e->set_state(f.state);
  e->set_finished(f.finished);
  for (const MutationTally& t : f.tallies) toProto(t, e->add_tallies());
  if (f.largeSteps.count != 0) toProto(f.largeSteps, e->mutable_large_steps());
}

void toProto(const MutationTally& tally, v1::MutationTally* out) {
  out->set_name(tally.name);
  out->set_proposed(tally.proposed);
  out->set_accepted(tally.accepted);
}

MutationTally fromProto(const v1::MutationTally& tally) {
  return MutationTally{tally.name(), tally.proposed(), tally.accepted()};
}

void toProto(const LargeStepSums& sums, v1::LargeStepSums* out) {
  out->set_count(sums.count);
  out->set_sum(sums.sum);
  out->set_sum_squares(sums.sumSquares);
}

LargeStepSums largeStepsFromProto(const v1::LargeStepSums& sums) {
  LargeStepSums s;
  s.count = sums.count();
  s.sum = sums.sum();
  s.sumSquares = sums.sum_squares();
  return s;
}

ChainFlush fromProto(const v1::FlushEntry& e) {
  return chainFlushFrom(e);
}

void toProto(const JobProgress& p, v1::JobProgress* m) {
  m->set_job_id(p.jobId);
  m->set_phase(toProto(p.phase));
  m->set_error(p.error);
  m->set_fraction(p.fraction);
  m->set_work_done(p.workDone);
  m->set_pilot_work(p.pilotWork);
  m->set_planned_work(p.plannedWork);
  m->set_samples_per_second(p.samplesPerSecond);
  m->set_elapsed_seconds(p.elapsedSeconds);
  m->set_eta_seconds(p.etaSeconds);
  m->set_normalization(p.normalization);
  m->set_normalization_std_error(p.normalizationStdError);
  m->set_bootstrap_seconds(p.bootstrapSeconds);
  m->set_bootstrap_candidates(p.bootstrapCandidates);
  m->set_large_steps(p.largeSteps);
  m->set_abandoned_connections(p.abandonedConnections);
  m->set_chains_total(p.chainsTotal);
  m->set_chains_finished(p.chainsFinished);
  m->set_chains_leased(p.chainsLeased);
  m->set_active_workers(p.activeWorkers);
  m->set_has_reference(p.hasReference);
  for (const ErrorSample& e : p.errorSeries) {
    v1::ErrorSample* s = m->add_error_series();
    s->set_elapsed_seconds(e.elapsedSeconds);
    s->set_samples(e.samples);
    s->set_rmse(e.rmse);
    s->set_relmse(e.relMse);
    s->set_estimated_relmse(e.estimatedRelMse);
  }
  m->set_error_series_total(p.errorSeriesTotal);
  m->set_rejected_splats(p.rejected.total());
  m->set_rejected_nan(p.rejected.nan);
  m->set_rejected_infinite(p.rejected.infinite);
  m->set_rejected_negative(p.rejected.negative);
  for (const MutationTally& t : p.tallies) toProto(t, m->add_tallies());
  for (const std::string& w : p.warnings) m->add_warnings(w);
  for (const std::string& line : p.renderPlan) m->add_render_plan(line);
  for (const std::string& w : p.setAside) m->add_set_aside(w);
  m->set_width(p.width);
  m->set_height(p.height);
  *m->mutable_settings() = toProto(p.settings, WithAllocation::kLeftOut);
  m->set_name(p.name);
  m->set_render_seconds(p.renderSeconds);
  m->set_load_seconds(p.loadSeconds);
  m->set_rays(p.rays);
  m->set_rays_per_second(p.raysPerSecond);
}

void fromProto(const v1::JobProgress& m, JobProgress* p) {
  p->jobId = m.job_id();
  p->name = m.name();
  p->error = m.error();
  p->phase = fromProto(m.phase());
  p->fraction = m.fraction();
  p->samplesPerSecond = m.samples_per_second();
  p->elapsedSeconds = m.elapsed_seconds();
  p->etaSeconds = m.eta_seconds();
  p->workDone = m.work_done();
  p->pilotWork = m.pilot_work();
  p->plannedWork = m.planned_work();
  p->rejected.nan = m.rejected_nan();
  p->rejected.infinite = m.rejected_infinite();
  p->rejected.negative = m.rejected_negative();
  p->tallies.clear();  // *p may hold an earlier answer (status asks twice)
  for (const v1::MutationTally& t : m.tallies()) p->tallies.push_back(fromProto(t));
  p->warnings.assign(m.warnings().begin(), m.warnings().end());
  p->renderPlan.assign(m.render_plan().begin(), m.render_plan().end());
  p->setAside.assign(m.set_aside().begin(), m.set_aside().end());
  p->rays = m.rays();
  p->raysPerSecond = m.rays_per_second();
  p->normalization = m.normalization();
  p->normalizationStdError = m.normalization_std_error();
  p->loadSeconds = m.load_seconds();
  p->bootstrapSeconds = m.bootstrap_seconds();
  p->bootstrapCandidates = m.bootstrap_candidates();
  p->largeSteps = m.large_steps();
  p->abandonedConnections = m.abandoned_connections();
  p->renderSeconds = m.render_seconds();
  p->chainsTotal = m.chains_total();
  p->chainsFinished = m.chains_finished();
  p->chainsLeased = m.chains_leased();
  p->activeWorkers = m.active_workers();
  p->hasReference = m.has_reference();
  p->errorSeries.clear();
  for (const v1::ErrorSample& e : m.error_series()) {
    p->errorSeries.push_back(
        {e.elapsed_seconds(), e.samples(), e.rmse(), e.relmse(), e.estimated_relmse()});
  }
  p->errorSeriesTotal = m.error_series_total();
  p->width = m.width();
  p->height = m.height();
  std::string ignored;
  fromProto(m.settings(), &p->settings, &ignored);
}

}  // namespace farm
