#pragma once
// A report directory's page: the chart of relative MSE against seconds, one curve per job
// (drawn by tools/plot_error.py with matplotlib, PNG and SVG), and index.html, which shows the
// chart, a table of each job's figures and the final images side by side. `farm compare` writes
// one for several algorithms, `farm report` for one job.
#include <string>
#include <vector>

#include "coordinator/job.h"

namespace farm {

struct ReportEntry {
  std::string name;      // the curve's and column's name (the algorithm)
  JobProgress progress;  // final, with the whole error series
  // Relative to the report directory: the entry's error_vs_time.csv, its image preview (PNG;
  // empty when the job has no image) and its EXR.
  std::string csv, png, exr;
};

// Writes dir/error_vs_time.{png,svg} and dir/index.html for `entries` (each entry's CSV must be
// written). The chart needs python3 with matplotlib (deploy/install-deps.sh installs it):
// without it the page is written all the same, *warning says why it has no chart, and the
// result is still true. False with *error when the page cannot be written.
bool writeReportPage(const std::string& dir, const std::string& title, const std::string& scene,
                     const std::string& reference, const std::vector<ReportEntry>& entries,
                     std::string* warning, std::string* error);

// The Python interpreter the chart runs with: $FARM_PYTHON, else /usr/bin/python3 (Debian's,
// with python3-matplotlib), else python3 on the PATH.
std::string reportPython();

}  // namespace farm
