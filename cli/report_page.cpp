#include "cli/report_page.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace farm {

namespace fs = std::filesystem;

namespace {

std::string escapeHtml(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string number(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Runs argv (no shell), its stdout and stderr into *output; the exit status, or -1 when it
// cannot start.
int runProgram(const std::vector<std::string>& argv, std::string* output) {
  int pipeFds[2];
  if (pipe(pipeFds) != 0) return -1;
  const pid_t pid = fork();
  if (pid < 0) {
    close(pipeFds[0]);
    close(pipeFds[1]);
    return -1;
  }
  if (pid == 0) {
    dup2(pipeFds[1], STDOUT_FILENO);
    dup2(pipeFds[1], STDERR_FILENO);
    close(pipeFds[0]);
    close(pipeFds[1]);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(pipeFds[1]);
  char buffer[4096];
  ssize_t n;
  while ((n = read(pipeFds[0], buffer, sizeof(buffer))) > 0) output->append(buffer, size_t(n));
  close(pipeFds[0]);
  int status = 0;
  if (waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string cell(double value) {
  return value < 0 ? "&ndash;" : number("%.4g", value);
}

const ErrorSample* lastWith(const JobProgress& p, bool measured) {
  for (auto it = p.errorSeries.rbegin(); it != p.errorSeries.rend(); ++it) {
    if ((measured ? it->relMse : it->estimatedRelMse) >= 0) return &*it;
  }
  return nullptr;
}

}  // namespace

std::string reportPython() {
  if (const char* python = std::getenv("FARM_PYTHON"); python && *python) return python;
  if (access("/usr/bin/python3", X_OK) == 0) return "/usr/bin/python3";
  return "python3";
}

bool writeReportPage(const std::string& dir, const std::string& title, const std::string& scene,
                     const std::string& reference, const std::vector<ReportEntry>& entries,
                     std::string* warning, std::string* error) {
  // The chart, by matplotlib (FARM_TOOLS_DIR: this source tree's tools/).
  std::vector<std::string> argv = {reportPython(), std::string(FARM_TOOLS_DIR) + "/plot_error.py",
                                   (fs::path(dir) / "error_vs_time").string()};
  for (const ReportEntry& e : entries) {
    argv.push_back(e.name + "=" + (fs::path(dir) / e.csv).string());
  }
  std::string output;
  const int rc = runProgram(argv, &output);
  const bool chart = rc == 0;
  if (!chart) {
    *warning = "no chart: " + argv[0] + " " + argv[1] + " " +
               (rc < 0 ? std::string("did not run") : "exited with " + std::to_string(rc)) +
               (output.empty() ? "" : " (" + output.substr(0, 400) + ")") +
               "; it needs python3-matplotlib (deploy/install-deps.sh installs it)";
  }

  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
       << escapeHtml(title) << "</title>\n<style>\n"
       << "body{font-family:sans-serif;margin:2em;max-width:80em}"
       << "table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:.3em .6em;"
       << "text-align:right}th:first-child,td:first-child{text-align:left}"
       << "figure{display:inline-block;margin:.5em;text-align:center}"
       << "figure img{image-rendering:pixelated;width:256px}\n</style></head><body>\n";
  html << "<h1>" << escapeHtml(title) << "</h1>\n<p>Scene: <code>" << escapeHtml(scene)
       << "</code>. Error against "
       << (reference.empty() ? std::string("no reference: the estimate from the spread between "
                                           "each job's chain groups (dashed)")
                             : "<code>" + escapeHtml(reference) + "</code>")
       << ".</p>\n";
  if (chart) {
    html << "<p><img src=\"error_vs_time.svg\" alt=\"relative MSE against seconds\"></p>\n";
  } else {
    html << "<p><em>" << escapeHtml(*warning) << "</em></p>\n";
  }
  html << "<table>\n<tr><th>algorithm</th><th>seconds</th><th>work</th><th>work/s</th>"
       << "<th>relMSE vs reference</th><th>estimated relMSE</th><th>Z</th>"
       << "<th>bootstrap share</th><th>data</th></tr>\n";
  for (const ReportEntry& e : entries) {
    const JobProgress& p = e.progress;
    const ErrorSample* measured = lastWith(p, true);
    const ErrorSample* estimated = lastWith(p, false);
    html << "<tr><td>" << escapeHtml(e.name) << "</td><td>" << number("%.2f", p.elapsedSeconds)
         << "</td><td>" << p.workDone << "</td><td>" << number("%.4g", p.samplesPerSecond)
         << "</td><td>" << cell(measured ? measured->relMse : -1) << "</td><td>"
         << cell(estimated ? estimated->estimatedRelMse : -1) << "</td><td>"
         << (p.normalization > 0 ? number("%.6g", p.normalization) + " &plusmn; " +
                                       number("%.2g", p.normalizationStdError)
                                 : "&ndash;")
         << "</td><td>"
         << (p.normalization > 0 && p.elapsedSeconds > 0
                 ? number("%.1f%%", 100 * p.bootstrapSeconds / p.elapsedSeconds)
                 : "&ndash;")
         << "</td><td><a href=\"" << escapeHtml(e.csv) << "\">CSV</a>"
         << (e.exr.empty() ? "" : " <a href=\"" + escapeHtml(e.exr) + "\">EXR</a>")
         << "</td></tr>\n";
  }
  html << "</table>\n<h2>Final images</h2>\n";
  for (const ReportEntry& e : entries) {
    html << "<figure>";
    if (!e.png.empty()) {
      html << "<img src=\"" << escapeHtml(e.png) << "\" alt=\"" << escapeHtml(e.name) << "\">";
    } else {
      html << "<p>(no image: " << escapeHtml(jobPhaseName(e.progress.phase)) << ")</p>";
    }
    html << "<figcaption>" << escapeHtml(e.name) << "</figcaption></figure>\n";
  }
  html << "<h2>Plans</h2>\n";
  for (const ReportEntry& e : entries) {
    html << "<h3>" << escapeHtml(e.name) << "</h3>\n<pre>";
    for (const std::string& line : e.progress.renderPlan) html << escapeHtml(line) << "\n";
    if (e.progress.renderPlan.empty()) html << "(no plan: the job did not get that far)\n";
    html << "</pre>\n";
  }
  html << "</body></html>\n";
  const std::string path = (fs::path(dir) / "index.html").string();
  std::ofstream out(path);
  out << html.str();
  out.close();
  if (!out) {
    *error = "cannot write '" + path + "'";
    return false;
  }
  return true;
}

}  // namespace farm
