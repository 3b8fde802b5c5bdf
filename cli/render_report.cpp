#include "cli/render_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace farm {
namespace {

std::string format(const char* fmt, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), fmt, value);
  return buffer;
}

// Z's relative standard error above which the report suggests a larger bootstrap, and the error
// it suggests one for.
constexpr double kZErrorToMention = 0.01;
constexpr double kZErrorAim = 0.005;

double relativeZError(const JobProgress& p) {
  return p.normalization > 0 ? p.normalizationStdError / p.normalization : 0.0;
}

// The relative error of an average pixel after the work done, were every unit of work one
// independent splat: 1/sqrt(work per pixel). A model: chains' correlation makes it larger, BDPT's
// strategies and expected-value splatting (several splats a mutation) smaller.
double pixelErrorModel(const JobProgress& p) {
  const double perPixel = p.width > 0 && p.height > 0 ? double(p.workDone) / p.width / p.height : 0;
  return perPixel > 0 ? 1 / std::sqrt(perPixel) : 0.0;
}

const char* workUnit(const RenderSettings& s) {
  if (s.algorithm == Algorithm::ERPT) return "seeds";
  return isMarkovChain(s.algorithm) ? "mutations" : "samples";
}

}  // namespace

std::string formatDuration(double seconds) {
  if (!(seconds >= 0) || !std::isfinite(seconds)) return "--:--";
  long total = long(std::llround(seconds));
  char buffer[32];
  if (total >= 3600) {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld:%02ld", total / 3600, (total / 60) % 60,
                  total % 60);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%ld:%02ld", total / 60, total % 60);
  }
  return buffer;
}

std::string formatCount(double value) {
  if (value >= 1e9) return format("%.2fG", value / 1e9);
  if (value >= 1e6) return format("%.2fM", value / 1e6);
  if (value >= 1e4) return format("%.1fk", value / 1e3);
  return format("%.0f", value);
}

// "  rejected splats: 12 (NaN 10, infinite 2, negative 0)\n", or nothing when there are none.
std::string rejectedLine(const JobProgress& p) {
  if (p.rejected.total() == 0) return "";
  return "  rejected splats: " + std::to_string(p.rejected.total()) + " (NaN " +
         std::to_string(p.rejected.nan) + ", infinite " + std::to_string(p.rejected.infinite) +
         ", negative " + std::to_string(p.rejected.negative) + ")\n";
}

// "  scene warning: FILE:LINE: ...\n" for each of the loader's warnings, then a line for each
// worker the job set aside.
std::string warningLines(const JobProgress& p) {
  std::string s;
  for (const std::string& w : p.warnings) s += "  scene warning: " + w + "\n";
  for (const std::string& w : p.setAside) s += "  " + w + "\n";
  return s;
}

// "  plan:\n    LINE\n..." with the scene's plan, or nothing before the job has one.
std::string planLines(const JobProgress& p) {
  if (p.renderPlan.empty()) return "";
  std::string s = "  plan:\n";
  for (const std::string& line : p.renderPlan) s += "    " + line + "\n";
  return s;
}

// "  acceptance: bidir 12.3% of 1.2M, lens 64.0% of 3.4M\n", or nothing without tallies.
std::string acceptanceLine(const JobProgress& p) {
  if (p.tallies.empty()) return "";
  std::string line = "  acceptance:";
  bool first = true;
  for (const MutationTally& t : p.tallies) {
    // The causes of lost manifold walks (common/mcmc/mutations/manifold_walk.h) that never
    // happened say nothing.
    if (t.accepted == 0 && t.name.rfind("walks lost", 0) == 0) continue;
    line += (first ? " " : ", ") + t.name + " " +
            format("%.1f", t.proposed > 0 ? 100.0 * t.accepted / t.proposed : 0.0) + "% of " +
            formatCount(double(t.proposed));
    first = false;
  }
  return line + "\n";
}

// A CSV value that may be absent (< 0).
static std::string csvValue(double v) {
  return v < 0 ? std::string() : format("%.9g", v);
}

std::string progressLine(const JobProgress& p, int barWidth) {
  std::string line = "[";
  const int filled = int(p.fraction * barWidth);
  for (int i = 0; i < barWidth; ++i) line += i < filled ? '=' : (i == filled ? '>' : ' ');
  line += "] " + format("%5.1f%%", 100 * p.fraction);
  if (p.phase != JobPhase::kRendering) line += std::string("  ") + jobPhaseName(p.phase);
  line += "  " + formatCount(p.samplesPerSecond) + " samples/s";
  line += "  elapsed " + formatDuration(p.elapsedSeconds);
  line += "  ETA " + formatDuration(p.etaSeconds);
  if (const ErrorSample* e = latestMeasured(p)) {
    line += "  rmse " + format("%.4g", e->rmse) + "  relMSE " + format("%.4g", e->relMse);
  }
  if (const ErrorSample* e = latestEstimated(p)) {
    line += "  est. relMSE " + format("%.3g", e->estimatedRelMse);
  }
  if (p.phase == JobPhase::kRendering)
    line += "  " + std::to_string(p.activeWorkers) + " worker(s)";
  return line;
}

// The reference-free estimate (common/film/batch_means.h), and the target it stops at.
static std::string estimateLine(const JobProgress& p) {
  std::string line;
  if (const ErrorSample* e = latestEstimated(p)) {
    line = "  error estimate (from the spread between chain groups, no reference): relMSE " +
           format("%.4g", e->estimatedRelMse) + " (at " + format("%.1f", e->elapsedSeconds) + " s)";
  } else if (p.settings.untilError > 0) {
    line = "  error estimate: not yet (every chain group needs work to show)";
  }
  if (!line.empty() && p.settings.untilError > 0) {
    line += "; stops at " + format("%.4g", p.settings.untilError);
  }
  return line.empty() ? line : line + "\n";
}

std::string statusText(const JobProgress& p) {
  std::ostringstream out;
  out << "job " << p.jobId << ": " << jobPhaseName(p.phase) << ", "
      << format("%.1f", 100 * p.fraction) << "% done\n";
  if (!p.error.empty()) out << "  error: " << p.error << "\n";
  out << "  scene: " << p.name << " (" << algorithmName(p.settings.algorithm);
  if (p.width > 0) out << ", " << p.width << "x" << p.height;
  out << ", seed " << p.settings.seed << ")\n";
  out << "  " << workUnit(p.settings) << ": " << p.workDone;
  if (p.plannedWork > 0) out << " of " << p.plannedWork;
  if (p.pilotWork > 0) out << " (" << p.pilotWork << " of them the pilot's)";
  if (p.settings.timeBudgetSeconds > 0) {
    out << " (time budget " << format("%g", p.settings.timeBudgetSeconds) << " s)";
  }
  out << ", " << formatCount(p.samplesPerSecond) << " samples/s, " << formatCount(p.raysPerSecond)
      << " rays/s\n";
  out << "  elapsed " << formatDuration(p.elapsedSeconds) << ", ETA "
      << formatDuration(p.etaSeconds) << "\n";
  out << "  chains: " << p.chainsFinished << " of " << p.chainsTotal << " finished, "
      << p.chainsLeased << " running on " << p.activeWorkers << " worker(s)\n";
  if (needsBootstrap(p.settings.algorithm) && p.normalization > 0) {
    out << "  Z = " << format("%.6g", p.normalization) << " +- "
        << format("%.3g", p.normalizationStdError) << " (bootstrap "
        << format("%.2f", p.bootstrapSeconds) << " s)\n";
  }
  out << acceptanceLine(p);
  out << rejectedLine(p);
  out << warningLines(p);
  out << planLines(p);
  if (const ErrorSample* e = latestMeasured(p)) {
    out << "  error vs reference: rmse " << format("%.6g", e->rmse) << ", relMSE "
        << format("%.6g", e->relMse) << " (at " << format("%.1f", e->elapsedSeconds) << " s)\n";
  } else if (p.hasReference) {
    out << "  error vs reference: not measured yet\n";
  }
  out << estimateLine(p);
  return out.str();
}

std::string finalReport(const JobProgress& p, const std::string& scene,
                        const std::string& referencePath) {
  std::ostringstream out;
  const RenderSettings& s = p.settings;
  out << "render: " << scene << ", " << algorithmName(s.algorithm) << ", " << p.width << "x"
      << p.height << ", seed " << s.seed;
  // Only where --max-depth overrode the file: the file's own depth is in the EXR's metadata.
  if (s.maxDepth > 0) out << ", paths of at most " << s.maxDepth << " edges (--max-depth)";
  if (s.maxDepth < 0) out << ", paths of any length (--max-depth -1)";
  out << "\n";
  const double pixels = double(p.width) * p.height;
  const double zError = relativeZError(p);
  if (needsBootstrap(s.algorithm)) {
    // Z scales every pixel alike, so its error is set beside the model of an average pixel's
    // own that sized it (common/mcmc/bootstrap_size.h); the error line below, with a
    // reference, gives the measured share.
    out << "  Z = " << format("%.6g", p.normalization) << " +- "
        << format("%.3g", p.normalizationStdError) << " (standard error "
        << format("%.3g", 100 * zError) << "%, from " << p.bootstrapCandidates << " candidates"
        << (p.largeSteps > 0 ? " and " + std::to_string(p.largeSteps) + " large steps" : "")
        << "; an average pixel's at one splat per unit of work: "
        << format("%.3g", 100 * pixelErrorModel(p)) << "%)\n";
    // Each a path its estimator would have found in fewer than one in 10^4 trials: left out of
    // Z, a bias of about that share of a candidate's light each (manifold_next_event.h).
    if (p.abandonedConnections > 0)
      out << "  manifold next-event estimation gave up on " << p.abandonedConnections
          << " connection(s) among the candidates (paths found in fewer than one in 10^4 "
             "trials, left out of Z)\n";
    // Z sets the whole image's brightness, so its error is what one render's channel means are
    // off by, however long the chains run (mlt's index-4 water at 60 s: Z 1.4-1.7% off, the
    // means 2.2-2.5% in two of three seeds; docs/specular.md). Above 1%, say what halving it
    // and more would cost: the error falls as the square root of the candidates.
    if (zError > kZErrorToMention && p.bootstrapCandidates > 0) {
      const double factor = std::pow(zError / kZErrorAim, 2);
      const int64_t wanted = std::min(int64_t(std::ceil(factor * double(p.bootstrapCandidates))),
                                      kMaxBootstrapSamples);
      const double ratio = double(wanted) / double(p.bootstrapCandidates);
      out << "  the image's brightness is uncertain by Z's " << format("%.3g", 100 * zError)
          << "%: --bootstrap-candidates " << wanted << " would bring that to about "
          << format("%.2g", 100 * zError / std::sqrt(ratio)) << "%, at about "
          << format("%.0f", p.bootstrapSeconds * ratio) << " s of bootstrap\n";
    }
  }
  out << "  " << workUnit(s) << ": " << p.workDone << " ("
      << format("%.2f", pixels > 0 ? p.workDone / pixels : 0) << " per pixel), "
      << formatCount(p.samplesPerSecond) << "/s over " << p.chainsTotal << " chains";
  if (p.pilotWork > 0) out << ", " << p.pilotWork << " of them the allocation pilot's";
  out << "\n";
  out << "  time: " << format("%.2f", p.elapsedSeconds) << " s total (load "
      << format("%.2f", p.loadSeconds) << " s, bootstrap " << format("%.2f", p.bootstrapSeconds)
      << " s = "
      << format("%.1f", p.elapsedSeconds > 0 ? 100 * p.bootstrapSeconds / p.elapsedSeconds : 0)
      << "% of the total, rendering " << format("%.2f", p.renderSeconds) << " s)\n";
  out << "  rays: " << p.rays << " (" << formatCount(p.raysPerSecond)
      << " rays/s while rendering)\n";
  out << rejectedLine(p);
  out << acceptanceLine(p);
  out << warningLines(p);
  out << planLines(p);
  if (const ErrorSample* e = latestMeasured(p)) {
    out << "  error vs " << referencePath << ": rmse " << format("%.6g", e->rmse) << ", relMSE "
        << format("%.6g", e->relMse);
    if (needsBootstrap(s.algorithm) && e->relMse > 0) {
      out << " (Z's standard error alone would make about "
          << format("%.2g", 100 * zError * zError / e->relMse) << "% of it)";
    }
    out << "\n";
  }
  out << estimateLine(p);
  return out.str();
}

bool writeReportDir(const std::string& dir, const JobProgress& p, const std::string& scene,
                    const std::string& output, const std::string& referencePath,
                    std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    *error = "cannot create report directory '" + dir + "': " + ec.message();
    return false;
  }
  const std::string csvPath = (fs::path(dir) / "error_vs_time.csv").string();
  std::ofstream csv(csvPath);
  // rmse and relmse against the reference, estimated_relmse from the chain groups' spread;
  // empty where not measured.
  csv << "elapsed_seconds,samples,rmse,relmse,estimated_relmse\n";
  for (const ErrorSample& e : p.errorSeries) {
    csv << format("%.6f", e.elapsedSeconds) << "," << e.samples << "," << csvValue(e.rmse) << ","
        << csvValue(e.relMse) << "," << csvValue(e.estimatedRelMse) << "\n";
  }
  csv.close();
  if (!csv) {
    *error = "cannot write '" + csvPath + "'";
    return false;
  }

  nlohmann::json j = progressJson(p);
  j["scene"] = scene;
  j["output"] = output;
  j["reference"] = referencePath.empty() ? nlohmann::json(nullptr) : nlohmann::json(referencePath);
  j["settings"] = {
      {"algorithm", algorithmName(p.settings.algorithm)},
      {"width", p.settings.width},
      {"height", p.settings.height},
      {"samples_per_pixel", p.settings.samplesPerPixel},
      {"mutations_per_pixel", p.settings.mutationsPerPixel},
      {"time_budget_seconds", p.settings.timeBudgetSeconds},
      {"seed", p.settings.seed},
      {"max_depth", p.settings.maxDepth},
      {"bootstrap_samples", p.settings.bootstrapSamples},
      {"flush_interval", p.settings.flushInterval},
      {"num_chains", p.settings.numChains},
      {"large_step_probability", p.settings.largeStepProbability},
      {"combine_large_steps", p.settings.combineLargeSteps},
      {"until_error", p.settings.untilError},
      {"mutation_mix", formatMutationMix(p.settings.mutationMix)},
  };
  j["bootstrap_share"] = p.elapsedSeconds > 0 ? p.bootstrapSeconds / p.elapsedSeconds : 0.0;
  j["normalization_relative_std_error"] = relativeZError(p);
  j["pixel_error_model"] = pixelErrorModel(p);
  j["error_vs_time"] = errorSeriesJson(p);
  const std::string jsonPath = (fs::path(dir) / "report.json").string();
  std::ofstream out(jsonPath);
  out << j.dump(2) << "\n";
  out.close();
  if (!out) {
    *error = "cannot write '" + jsonPath + "'";
    return false;
  }
  return true;
}

}  // namespace farm
