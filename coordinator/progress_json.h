#pragma once
// A job's progress as JSON: `farm status --json`, the report directory's report.json and the
// coordinator's web page (/api/jobs) all say it the same way.
#include <nlohmann/json.hpp>

#include "coordinator/job.h"

namespace farm {

// The latest sample that measured the error against the reference, or that estimated it
// without one; null when there is none.
const ErrorSample* latestMeasured(const JobProgress& progress);
const ErrorSample* latestEstimated(const JobProgress& progress);
// A value that may be absent (< 0): null then.
nlohmann::json jsonValue(double value);

nlohmann::json progressJson(const JobProgress& progress);
// The error series, one object per sample (elapsed_seconds, samples, rmse, relmse,
// estimated_relmse; absent values null).
nlohmann::json errorSeriesJson(const JobProgress& progress);

}  // namespace farm
