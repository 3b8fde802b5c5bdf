#include "coordinator/progress_json.h"

namespace farm {

const ErrorSample* latestMeasured(const JobProgress& p) {
  for (auto it = p.errorSeries.rbegin(); it != p.errorSeries.rend(); ++it)
    if (it->relMse >= 0) return &*it;
  return nullptr;
}

const ErrorSample* latestEstimated(const JobProgress& p) {
  for (auto it = p.errorSeries.rbegin(); it != p.errorSeries.rend(); ++it)
    if (it->estimatedRelMse >= 0) return &*it;
  return nullptr;
}

nlohmann::json jsonValue(double v) {
  return v < 0 ? nlohmann::json(nullptr) : nlohmann::json(v);
}

nlohmann::json progressJson(const JobProgress& p) {
  nlohmann::json j;
  j["job_id"] = p.jobId;
  j["phase"] = jobPhaseName(p.phase);
  j["error"] = p.error;
  j["name"] = p.name;
  j["algorithm"] = algorithmName(p.settings.algorithm);
  j["width"] = p.width;
  j["height"] = p.height;
  j["seed"] = p.settings.seed;
  j["fraction"] = p.fraction;
  j["work_done"] = p.workDone;
  j["pilot_work"] = p.pilotWork;
  j["planned_work"] = p.plannedWork;
  j["samples_per_second"] = p.samplesPerSecond;
  j["elapsed_seconds"] = p.elapsedSeconds;
  j["eta_seconds"] = p.etaSeconds;
  j["normalization"] = p.normalization;
  j["normalization_std_error"] = p.normalizationStdError;
  j["load_seconds"] = p.loadSeconds;
  j["bootstrap_seconds"] = p.bootstrapSeconds;
  j["bootstrap_candidates"] = p.bootstrapCandidates;
  j["large_steps"] = p.largeSteps;  // pooled into normalization with the candidates
  j["abandoned_connections"] = p.abandonedConnections;
  j["render_seconds"] = p.renderSeconds;
  j["chains_total"] = p.chainsTotal;
  j["chains_finished"] = p.chainsFinished;
  j["chains_leased"] = p.chainsLeased;
  j["active_workers"] = p.activeWorkers;
  j["rejected_splats"] = {{"total", p.rejected.total()},
                          {"nan", p.rejected.nan},
                          {"infinite", p.rejected.infinite},
                          {"negative", p.rejected.negative}};
  j["rays"] = p.rays;
  j["rays_per_second"] = p.raysPerSecond;
  j["has_reference"] = p.hasReference;
  j["warnings"] = p.warnings;
  j["render_plan"] = p.renderPlan;
  j["set_aside"] = p.setAside;
  nlohmann::json tallies = nlohmann::json::object();
  for (const MutationTally& t : p.tallies) {
    tallies[t.name] = {{"proposed", t.proposed},
                       {"accepted", t.accepted},
                       {"acceptance", t.proposed > 0 ? double(t.accepted) / t.proposed : 0.0}};
  }
  j["mutations"] = tallies;
  const ErrorSample* measured = latestMeasured(p);
  j["rmse"] = measured ? jsonValue(measured->rmse) : nlohmann::json(nullptr);
  j["relmse"] = measured ? jsonValue(measured->relMse) : nlohmann::json(nullptr);
  const ErrorSample* estimated = latestEstimated(p);
  j["estimated_relmse"] =
      estimated ? jsonValue(estimated->estimatedRelMse) : nlohmann::json(nullptr);
  j["until_error"] = jsonValue(p.settings.untilError > 0 ? p.settings.untilError : -1);
  return j;
}

nlohmann::json errorSeriesJson(const JobProgress& p) {
  nlohmann::json series = nlohmann::json::array();
  for (const ErrorSample& e : p.errorSeries) {
    series.push_back({{"elapsed_seconds", e.elapsedSeconds},
                      {"samples", e.samples},
                      {"rmse", jsonValue(e.rmse)},
                      {"relmse", jsonValue(e.relMse)},
                      {"estimated_relmse", jsonValue(e.estimatedRelMse)}});
  }
  return series;
}

}  // namespace farm
