#pragma once
// How the farm command shows a job: the progress bar, `farm status` text and JSON, the final
// report of `farm render`, and the --report directory (error_vs_time.csv, report.json).
#include <nlohmann/json.hpp>
#include <string>

#include "coordinator/job.h"
#include "coordinator/progress_json.h"  // progressJson

namespace farm {

std::string formatDuration(double seconds);  // "0:07", "12:34", "1:02:03"; "--:--" if < 0
std::string formatCount(double value);       // "950", "12.3k", "4.56M", "7.89G"

// One line: bar, percent, samples/s, elapsed, ETA, latest error against the reference.
std::string progressLine(const JobProgress& progress, int barWidth = 30);
// Several lines for `farm status`.
std::string statusText(const JobProgress& progress);

// The closing report of `farm render` (and `farm fetch`): Z with its error, the bootstrap's
// share of the time, samples, time, error against the reference.
std::string finalReport(const JobProgress& progress, const std::string& scene,
                        const std::string& referencePath);

// Writes dir/error_vs_time.csv (elapsed_seconds,samples,rmse,relmse; one row per measured flush)
// and dir/report.json. False with *error when the directory cannot be written.
bool writeReportDir(const std::string& dir, const JobProgress& progress, const std::string& scene,
                    const std::string& output, const std::string& referencePath,
                    std::string* error);

}  // namespace farm
