#pragma once
// `farm compare` and `farm report`: error against run time you can see. compare renders one
// scene with each of several algorithms for the same settings and budget, here (embedded) or on
// a coordinator, one job after another so that each has the machine to itself; report collects
// one coordinator job's. Both write a report directory:
//
//   DIR/<algorithm>/error_vs_time.csv, report.json, image.exr, image.png   per job
//   DIR/error_vs_time.png and .svg    relative MSE against seconds, log-log, a curve a job
//   DIR/summary.json                  each job's final figures
//   DIR/index.html                    the chart, the figures and the images side by side
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "cli/report_page.h"
#include "coordinator/status.h"
#include "proto/transport_security.h"

namespace farm {

// One job of a comparison: an algorithm, or auto (the plan's pick; with --pilot, its pilot's).
struct AlgorithmChoice {
  Algorithm algorithm = Algorithm::PSSMLT;
  bool automatic = false;
  std::string name() const { return automatic ? "auto" : algorithmName(algorithm); }
};

struct CompareOptions {
  std::string scene, reference, reportDir;
  std::string coordinator;  // HOST:PORT, or empty: render here
  ClientSecurity security;  // what to present to that coordinator
  std::vector<AlgorithmChoice> algorithms;
  RenderSettings settings;  // all but the algorithm, shared by every job
  int threads = 1;          // embedded
  std::function<void(const std::string& name, const JobProgress&)> onProgress;
  const std::atomic<bool>* interrupted = nullptr;
};

struct CompareResult {
  std::vector<ReportEntry> entries;
  std::string warning;  // the page has no chart, and why
};

// Stops at the first job that fails (its message, naming the algorithm).
Status runCompare(const CompareOptions& options, CompareResult* result);

// `farm report JOB DIR`: a coordinator job's series, settings and (once done) image, as a
// report directory of one entry.
Status runJobReport(const std::string& coordinator, const ClientSecurity& security,
                    const std::string& jobId, const std::string& reportDir, CompareResult* result);

// "pt,bdpt,mlt,auto" -> algorithms, each once, in order; false with *error naming the bad one.
bool parseAlgorithms(const std::string& list, std::vector<AlgorithmChoice>* out,
                     std::string* error);

}  // namespace farm
