#include "cli/compare.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cli/embedded_render.h"
#include "cli/farm_client.h"
#include "cli/render_report.h"
#include "cli/scene_bundle.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

// The job's files in DIR/<name>/ and its entry; the image is optional (a job without one).
Status writeEntry(const std::string& dir, const std::string& name, const JobProgress& progress,
                  const Image* image, const ImageMetadata& metadata, const std::string& scene,
                  const std::string& reference, ReportEntry* entry) {
  const fs::path sub = fs::path(dir) / name;
  std::error_code ec;
  fs::create_directories(sub, ec);
  if (ec) return Status::internal("cannot create '" + sub.string() + "': " + ec.message());
  entry->name = name;
  entry->progress = progress;
  entry->csv = name + "/error_vs_time.csv";
  std::string error;
  if (image) {
    entry->exr = name + "/image.exr";
    entry->png = name + "/image.png";
    if (!writeExr((sub / "image.exr").string(), *image, metadata, &error) ||
        !writePreview((sub / "image.png").string(), *image, &error)) {
      return Status::internal(error);
    }
  }
  if (!writeReportDir(sub.string(), progress, scene, image ? entry->exr : "", reference, &error)) {
    return Status::internal(error);
  }
  return Status::ok();
}

Status writeSummaryAndPage(const std::string& dir, const std::string& title,
                           const std::string& scene, const std::string& reference,
                           CompareResult* result) {
  nlohmann::json summary = nlohmann::json::array();
  for (const ReportEntry& e : result->entries) {
    nlohmann::json j = progressJson(e.progress);
    j["name"] = e.name;
    j["csv"] = e.csv;
    j["image"] = e.exr.empty() ? nlohmann::json(nullptr) : nlohmann::json(e.exr);
    summary.push_back(j);
  }
  const std::string path = (fs::path(dir) / "summary.json").string();
  std::ofstream out(path);
  out << summary.dump(2) << "\n";
  out.close();
  if (!out) return Status::internal("cannot write '" + path + "'");
  std::string error;
  if (!writeReportPage(dir, title, scene, reference, result->entries, &result->warning, &error))
    return Status::internal(error);
  return Status::ok();
}

// Polls a coordinator job to its end; the whole error series at the end.
Status followRemote(FarmClient& client, const std::string& job, const std::string& name,
                    const CompareOptions* options, JobProgress* p) {
  for (;;) {
    Status s = client.progress(job, UINT32_MAX, p);
    if (s.isOk() && p->errorSeriesTotal > 0) s = client.progress(job, p->errorSeriesTotal - 1, p);
    if (!s.isOk()) return s;
    if (options && options->onProgress) options->onProgress(name, *p);
    if (isTerminal(p->phase)) break;
    if (options && options->interrupted && *options->interrupted) {
      JobPhase phase;
      client.cancel(job, &phase);
      return Status(StatusCode::kCancelled, "interrupted (job " + job + " cancelled)");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  return client.progress(job, 0, p);
}

// The job's image from the coordinator (once done), read back for the preview.
Status fetchRemoteImage(FarmClient& client, const std::string& job, const std::string& dir,
                        Image* image, ImageMetadata* metadata) {
  const std::string path = (fs::path(dir) / ("." + job + ".exr")).string();
  Status s = client.fetchImage(job, false, path);
  if (!s.isOk()) return s;
  std::string error;
  const bool read = readExr(path, image, &error, metadata);
  std::error_code ec;
  fs::remove(path, ec);
  return read ? Status::ok() : Status::internal(error);
}

}  // namespace

bool parseAlgorithms(const std::string& list, std::vector<AlgorithmChoice>* out,
                     std::string* error) {
  out->clear();
  std::stringstream in(list);
  std::string name;
  while (std::getline(in, name, ',')) {
    AlgorithmChoice a;
    a.automatic = name == "auto";
    if (!a.automatic && !parseAlgorithm(name, &a.algorithm)) {
      *error = "--algorithms: '" + name + "' is not one of " + algorithmList() + ", auto";
      return false;
    }
    for (const AlgorithmChoice& b : *out) {
      if (a.name() == b.name()) {
        *error = "--algorithms names " + name + " twice";
        return false;
      }
    }
    out->push_back(a);
  }
  if (out->empty()) {
    *error = "--algorithms names none (one or more of " + std::string(algorithmList()) + ", auto)";
    return false;
  }
  return true;
}

Status runCompare(const CompareOptions& o, CompareResult* result) {
  std::error_code ec;
  fs::create_directories(o.reportDir, ec);
  if (ec) return Status::internal("cannot create '" + o.reportDir + "': " + ec.message());
  std::unique_ptr<FarmClient> client;
  LocalBundle bundle;
  if (!o.coordinator.empty()) {
    client = std::make_unique<FarmClient>(o.coordinator, o.security);
    if (Status s = client->connect(5); !s.isOk()) return s;
    std::string error;
    if (!collectSceneBundle(o.scene, &bundle, &error, {})) return Status::invalidArgument(error);
  }
  for (const AlgorithmChoice& choice : o.algorithms) {
    const std::string name = choice.name();
    RenderSettings settings = o.settings;
    settings.algorithm = choice.algorithm;
    settings.autoAlgorithm = choice.automatic;
    settings.pilot = choice.automatic && o.settings.pilot;  // --pilot is auto's alone
    // --combine-large-steps is for the chains that have large steps (and auto, which may pick one)
    settings.combineLargeSteps = o.settings.combineLargeSteps &&
                                 (choice.automatic || isPrimarySampleSpace(choice.algorithm));
    JobProgress progress;
    Image image;
    ImageMetadata metadata;
    if (!client) {
      EmbeddedRenderOptions render;
      render.settings = settings;
      render.scenePath = o.scene;
      render.referencePath = o.reference;
      render.threads = o.threads;
      render.onProgress = [&](const JobProgress& p) {
        if (o.onProgress) o.onProgress(name, p);
      };
      render.interrupted = o.interrupted;
      EmbeddedRenderResult r;
      Status s = renderEmbedded(render, &r);
      if (!s.isOk()) return Status(s.code(), name + ": " + s.message());
      progress = std::move(r.progress);
      image = std::move(r.image);
      metadata = std::move(r.metadata);
    } else {
      Submission submission;
      submission.settings = settings;
      submission.bundle = bundle;
      submission.referencePath = o.reference;
      submission.name = fs::path(o.scene).filename().string() + " (compare " + name + ")";
      std::string job;
      Status s = client->submit(submission, &job);
      if (s.isOk()) s = followRemote(*client, job, name, &o, &progress);
      if (s.isOk() && progress.phase != JobPhase::kDone) {
        s = Status::internal("job " + job + " " + jobPhaseName(progress.phase) +
                             (progress.error.empty() ? "" : ": " + progress.error));
      }
      if (s.isOk()) s = fetchRemoteImage(*client, job, o.reportDir, &image, &metadata);
      if (!s.isOk()) return Status(s.code(), name + ": " + s.message());
    }
    ReportEntry entry;
    Status s =
        writeEntry(o.reportDir, name, progress, &image, metadata, o.scene, o.reference, &entry);
    if (!s.isOk()) return s;
    result->entries.push_back(std::move(entry));
  }
  return writeSummaryAndPage(o.reportDir, "farm compare: " + fs::path(o.scene).filename().string(),
                             o.scene, o.reference, result);
}

Status runJobReport(const std::string& coordinator, const ClientSecurity& security,
                    const std::string& jobId, const std::string& reportDir, CompareResult* result) {
  FarmClient client(coordinator, security);
  if (Status s = client.connect(5); !s.isOk()) return s;
  JobProgress progress;
  if (Status s = client.progress(jobId, 0, &progress); !s.isOk()) return s;
  std::error_code ec;
  fs::create_directories(reportDir, ec);
  if (ec) return Status::internal("cannot create '" + reportDir + "': " + ec.message());
  Image image;
  ImageMetadata metadata;
  const bool done = progress.phase == JobPhase::kDone;
  if (done) {
    if (Status s = fetchRemoteImage(client, jobId, reportDir, &image, &metadata); !s.isOk())
      return s;
  }
  ReportEntry entry;
  const std::string name = algorithmName(progress.settings.algorithm);
  if (Status s =
          writeEntry(reportDir, name, progress, done ? &image : nullptr, metadata, progress.name,
                     progress.hasReference ? "(uploaded reference)" : "", &entry);
      !s.isOk()) {
    return s;
  }
  result->entries.push_back(std::move(entry));
  return writeSummaryAndPage(reportDir, "farm report: job " + jobId + " (" + progress.name + ")",
                             progress.name, progress.hasReference ? "the job's reference" : "",
                             result);
}

}  // namespace farm
