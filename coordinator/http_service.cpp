#include "coordinator/http_service.h"

#include <httplib.h>
#include <openssl/evp.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "common/film/image.h"
#include "coordinator/coordinator.h"
#include "coordinator/progress_json.h"
#include "proto/transport_security.h"

namespace farm {
namespace {

// The page: plain HTML and a script that polls the JSON API (no build step, no framework).
const char kPage[] = R"HTML(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>farm</title>
<style>
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em}td,th{padding:.25em .8em;text-align:left;border-bottom:1px solid #ddd}
.bar{width:12em;height:.8em;background:#eee;display:inline-block;vertical-align:middle}
.bar>span{display:block;height:100%;background:#4a7}
#preview{image-rendering:pixelated;max-width:100%;border:1px solid #ccc}
pre{background:#f6f6f6;padding:.6em}
</style></head><body>
<h1><a href="#/">farm</a></h1>
<div id="view">loading...</div>
<script>
"use strict";
const view = document.getElementById("view");
const esc = s => String(s).replace(/[&<>"]/g, c => ({"&":"&amp;","<":"&lt;",">":"&gt;",'"':"&quot;"}[c]));
const dur = s => (s == null || s < 0) ? "--:--" :
  Math.floor(s / 60) + ":" + String(Math.round(s % 60)).padStart(2, "0");
const bar = f => `<span class="bar"><span style="width:${(100 * f).toFixed(1)}%"></span></span> ${(100 * f).toFixed(1)}%`;
async function get(path) {
  const r = await fetch(path, {cache: "no-store"});
  if (!r.ok) throw new Error(path + ": " + r.status + " " + await r.text());
  return r.json();
}
function curve(series) {
  // relMSE (or its estimate) against seconds, log-log, as an SVG polyline.
  const pts = series.map(e => [e.elapsed_seconds, e.relmse != null ? e.relmse : e.estimated_relmse])
    .filter(p => p[0] > 0 && p[1] > 0);
  if (pts.length < 2) return "<p>no error curve yet</p>";
  const lx = pts.map(p => Math.log10(p[0])), ly = pts.map(p => Math.log10(p[1]));
  const x0 = Math.min(...lx), x1 = Math.max(...lx) + 1e-9, y0 = Math.min(...ly), y1 = Math.max(...ly) + 1e-9;
  const W = 420, H = 220, m = 30;
  const xy = pts.map((p, i) => [m + (W - 2 * m) * (lx[i] - x0) / (x1 - x0), H - m - (H - 2 * m) * (ly[i] - y0) / (y1 - y0)]);
  return `<svg id="curve" width="${W}" height="${H}" style="border:1px solid #ccc">
    <polyline fill="none" stroke="#36a" stroke-width="2" points="${xy.map(p => p.join(",")).join(" ")}"/>
    <text x="${m}" y="${H - 8}" font-size="11">${pts[0][0].toPrecision(2)} s</text>
    <text x="${W - m - 40}" y="${H - 8}" font-size="11">${pts[pts.length - 1][0].toPrecision(3)} s</text>
    <text x="4" y="${m}" font-size="11">${Math.pow(10, y1).toPrecision(2)}</text>
    <text x="4" y="${H - m}" font-size="11">${Math.pow(10, y0).toPrecision(2)}</text></svg>
    <div>relative MSE${series.some(e => e.relmse != null) ? " against the reference" : " (estimate, no reference)"} against seconds, log-log</div>`;
}
async function showJobs() {
  const [jobs, workers] = await Promise.all([get("/api/jobs"), get("/api/workers")]);
  view.innerHTML = `<h2>jobs</h2><table id="jobs"><tr><th>job</th><th>scene</th><th>algorithm</th><th>phase</th><th>progress</th><th>samples/s</th><th>elapsed</th><th>ETA</th></tr>` +
    jobs.map(j => `<tr class="job"><td><a href="#/job/${esc(j.job_id)}">${esc(j.job_id)}</a></td><td>${esc(j.name)}</td>
      <td>${esc(j.algorithm)}</td><td class="phase">${esc(j.phase)}</td><td>${bar(j.fraction)}</td>
      <td>${Math.round(j.samples_per_second)}</td><td>${dur(j.elapsed_seconds)}</td><td>${dur(j.eta_seconds)}</td></tr>`).join("") +
    `</table><h2>workers</h2><table id="workers"><tr><th>worker</th><th>host</th><th>threads</th><th>chains</th><th>work/s</th><th>flushes</th><th>last contact</th></tr>` +
    workers.map(w => `<tr><td>${esc(w.id)}</td><td>${esc(w.host)}</td><td>${w.threads}</td><td>${w.chains}</td>
      <td>${Math.round(w.work_per_second)}</td><td>${w.flushes_accepted}</td><td>${w.last_contact_seconds.toFixed(1)} s ago</td></tr>`).join("") + `</table>`;
}
let previewJob = null, previewAt = 0;
async function showJob(id) {
  const j = await get("/api/jobs/" + encodeURIComponent(id));
  const now = Date.now();
  if (previewJob !== id || now - previewAt > 2000) { previewJob = id; previewAt = now; }
  view.innerHTML = `<h2>job <span id="job-id">${esc(j.job_id)}</span>: <span id="phase">${esc(j.phase)}</span></h2>
    <p>${bar(j.fraction)} &nbsp; ${Math.round(j.samples_per_second)} samples/s, elapsed ${dur(j.elapsed_seconds)},
      ETA ${dur(j.eta_seconds)}, ${j.active_workers} worker(s)${j.error ? ", error: " + esc(j.error) : ""}</p>
    <img id="preview" alt="no image yet" src="/api/jobs/${encodeURIComponent(id)}/preview.png?at=${previewAt}"
      width="${Math.max(256, j.width)}">
    <h3>error against time</h3>${curve(j.error_vs_time || [])}
    <h3>settings</h3><pre>${esc(JSON.stringify(j.settings, null, 1))}</pre>
    <h3>plan</h3><pre>${esc((j.render_plan || []).join("\n"))}</pre>
    <h3>report</h3><pre>${esc(JSON.stringify(Object.fromEntries(Object.entries(j).filter(([k]) =>
      !["settings", "render_plan", "error_vs_time"].includes(k))), null, 1))}</pre>`;
}
async function refresh() {
  try {
    const m = location.hash.match(/^#\/job\/(.+)$/);
    await (m ? showJob(decodeURIComponent(m[1])) : showJobs());
  } catch (e) { view.innerHTML = `<p class="error">${esc(e.message)}</p>`; }
}
window.addEventListener("hashchange", refresh);
refresh();
setInterval(refresh, 1000);
</script></body></html>
)HTML";

// "Basic base64(user:password)" as "Bearer password": a browser's login prompt carries the token.
std::string bearerFrom(const std::string& authorization) {
  const std::string basic = "Basic ";
  if (authorization.compare(0, basic.size(), basic) != 0) return authorization;
  const std::string encoded = authorization.substr(basic.size());
  std::string decoded(encoded.size(), '\0');
  const int n =
      EVP_DecodeBlock(reinterpret_cast<unsigned char*>(decoded.data()),
                      reinterpret_cast<const unsigned char*>(encoded.data()), int(encoded.size()));
  if (n < 0) return "";
  decoded.resize(size_t(n));
  while (!decoded.empty() && decoded.back() == '\0') decoded.pop_back();  // base64 padding
  const size_t colon = decoded.find(':');
  return colon == std::string::npos ? "" : "Bearer " + decoded.substr(colon + 1);
}

// A label value in the Prometheus text format.
std::string label(const std::string& value) {
  std::string out;
  for (char c : value) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

class HttplibService final : public HttpService {
 public:
  HttplibService(Coordinator* coordinator, const CallGuard* guard)
      : coordinator_(coordinator), guard_(guard) {}

  bool start(const std::string& address, const ServerSecurity& security, std::string* error) {
    if (!security.certFile.empty()) {
      // The files were checked when the gRPC listener loaded them; this is OpenSSL reading them
      // again for cpp-httplib.
      server_ =
          std::make_unique<httplib::SSLServer>(security.certFile.c_str(), security.keyFile.c_str());
      if (!server_->is_valid()) {
        *error = "cannot serve the web page over TLS with " + security.certFile + " and " +
                 security.keyFile;
        return false;
      }
      https_ = true;
    } else {
      server_ = std::make_unique<httplib::Server>();
    }
    const size_t colon = address.rfind(':');
    if (colon == std::string::npos) {
      *error = "--http '" + address + "' is not HOST:PORT";
      return false;
    }
    std::string host = address.substr(0, colon);
    if (host.size() > 2 && host.front() == '[') host = host.substr(1, host.size() - 2);
    const int wanted = std::atoi(address.c_str() + colon + 1);
    routes();
    port_ = wanted == 0 ? server_->bind_to_any_port(host)
                        : (server_->bind_to_port(host, wanted) ? wanted : -1);
    if (port_ <= 0) {
      *error = "cannot serve the web page on '" + address +
               "' (in use, or not an address of "
               "this host)";
      return false;
    }
    thread_ = std::thread([this] { server_->listen_after_bind(); });
    return true;
  }

  int port() const override { return port_; }
  bool https() const override { return https_; }

  void stop() override {
    if (!thread_.joinable()) return;
    server_->stop();
    thread_.join();
  }

  ~HttplibService() override { stop(); }

 private:
  // With a submit token, every request carries it; else a browser is asked to log in.
  bool allowed(const httplib::Request& request, httplib::Response& response) const {
    if (!guard_ || !guard_->asksToken(Role::kSubmit)) return true;
    const bool present = request.has_header("Authorization");
    CallCheck check =
        guard_->checkHeader(present ? bearerFrom(request.get_header_value("Authorization")) : "",
                            present, Role::kSubmit);
    if (check.ok()) return true;
    response.status = check.code == CallCheck::Code::kPermissionDenied ? 403 : 401;
    response.set_header("WWW-Authenticate", "Basic realm=\"farm (the submit token as password)\"");
    response.set_content(check.message + "\n", "text/plain");
    return false;
  }

  static void json(httplib::Response& response, const nlohmann::json& body) {
    response.set_header("Cache-Control", "no-store");
    response.set_content(body.dump(), "application/json");
  }

  static void fail(httplib::Response& response, const Status& status) {
    response.status = status.code() == StatusCode::kNotFound             ? 404
                      : status.code() == StatusCode::kFailedPrecondition ? 404
                                                                         : 500;
    response.set_content(status.message() + "\n", "text/plain");
  }

  nlohmann::json workersJson() const {
    nlohmann::json out = nlohmann::json::array();
    for (const WorkerStatus& w : coordinator_->workers()) {
      out.push_back({{"id", w.id},
                     {"host", w.host},
                     {"version", w.version},
                     {"threads", w.threads},
                     {"chains", w.chains},
                     {"work_accepted", w.workAccepted},
                     {"flushes_accepted", w.flushesAccepted},
                     {"work_per_second",
                      w.registeredSeconds > 0 ? double(w.workAccepted) / w.registeredSeconds : 0},
                     {"registered_seconds", w.registeredSeconds},
                     {"last_contact_seconds", w.lastContactSeconds}});
    }
    return out;
  }

  std::string metrics() const {
    std::ostringstream m;
    const std::vector<JobProgress> jobs = coordinator_->list();
    std::map<std::string, int> phases;
    for (JobPhase p : {JobPhase::kSubmitted, JobPhase::kLoadingScene, JobPhase::kBootstrapping,
                       JobPhase::kRendering, JobPhase::kFinishing, JobPhase::kDone,
                       JobPhase::kFailed, JobPhase::kCancelled}) {
      phases[jobPhaseName(p)] = 0;
    }
    for (const JobProgress& j : jobs) ++phases[jobPhaseName(j.phase)];
    m << "# HELP farm_jobs Jobs this coordinator holds, by phase.\n# TYPE farm_jobs gauge\n";
    for (const auto& [phase, n] : phases) m << "farm_jobs{phase=\"" << phase << "\"} " << n << "\n";
    auto perJob = [&](const char* name, const char* type, const char* help, auto value) {
      m << "# HELP " << name << " " << help << "\n# TYPE " << name << " " << type << "\n";
      for (const JobProgress& j : jobs) {
        m << name << "{job=\"" << label(j.jobId) << "\",algorithm=\""
          << algorithmName(j.settings.algorithm) << "\"} " << value(j) << "\n";
      }
    };
    perJob("farm_job_fraction", "gauge", "Fraction of the job done.",
           [](const JobProgress& j) { return j.fraction; });
    perJob("farm_job_work_done_total", "counter", "Mutations or samples accepted.",
           [](const JobProgress& j) { return j.workDone; });
    perJob("farm_job_samples_per_second", "gauge", "Work accepted per second.",
           [](const JobProgress& j) { return j.samplesPerSecond; });
    perJob("farm_job_chains_leased", "gauge", "Chains running on workers.",
           [](const JobProgress& j) { return j.chainsLeased; });
    perJob("farm_job_elapsed_seconds", "gauge", "Seconds since the job was submitted.",
           [](const JobProgress& j) { return j.elapsedSeconds; });
    const std::vector<WorkerStatus> workers = coordinator_->workers();
    m << "# HELP farm_workers Registered workers.\n# TYPE farm_workers gauge\nfarm_workers "
      << workers.size() << "\n";
    auto perWorker = [&](const char* name, const char* type, const char* help, auto value) {
      m << "# HELP " << name << " " << help << "\n# TYPE " << name << " " << type << "\n";
      for (const WorkerStatus& w : workers) {
        m << name << "{worker=\"" << label(w.id) << "\",host=\"" << label(w.host) << "\"} "
          << value(w) << "\n";
      }
    };
    perWorker("farm_worker_chains", "gauge", "Chain leases the worker holds.",
              [](const WorkerStatus& w) { return w.chains; });
    perWorker("farm_worker_work_accepted_total", "counter",
              "Mutations or samples of the worker's accepted flushes.",
              [](const WorkerStatus& w) { return w.workAccepted; });
    perWorker("farm_worker_flushes_accepted_total", "counter", "The worker's accepted flushes.",
              [](const WorkerStatus& w) { return w.flushesAccepted; });
    perWorker("farm_worker_last_contact_seconds", "gauge", "Seconds since the worker's last call.",
              [](const WorkerStatus& w) { return w.lastContactSeconds; });
    return m.str();
  }

  // The image as it stands, as PNG bytes (written through a temporary file: OpenImageIO's PNG
  // writer wants a file).
  bool preview(const std::string& jobId, std::string* png, Status* status) const {
    Image image;
    *status = coordinator_->currentImage(jobId, &image);
    if (!status->isOk()) return false;
    char pattern[] = "/tmp/farm-preview-XXXXXX";
    const int fd = mkstemp(pattern);
    if (fd < 0) {
      *status = Status::internal("cannot make a temporary file for the preview");
      return false;
    }
    close(fd);
    const std::string path = std::string(pattern) + ".png";
    std::string error;
    const bool written = writePreview(path, image, &error);
    std::remove(pattern);
    if (!written) {
      *status = Status::internal(error);
      return false;
    }
    std::ifstream in(path, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    *png = bytes.str();
    std::remove(path.c_str());
    return true;
  }

  void routes() {
    server_->Get("/", [this](const httplib::Request& q, httplib::Response& r) {
      if (!allowed(q, r)) return;
      r.set_content(kPage, "text/html; charset=utf-8");
    });
    server_->Get("/api/jobs", [this](const httplib::Request& q, httplib::Response& r) {
      if (!allowed(q, r)) return;
      nlohmann::json jobs = nlohmann::json::array();
      for (const JobProgress& p : coordinator_->list()) jobs.push_back(progressJson(p));
      json(r, jobs);
    });
    server_->Get(R"(/api/jobs/([A-Za-z0-9_-]{1,64}))",
                 [this](const httplib::Request& q, httplib::Response& r) {
                   if (!allowed(q, r)) return;
                   JobProgress p;
                   Status s = coordinator_->progress(q.matches[1], 0, &p);
                   if (!s.isOk()) return fail(r, s);
                   nlohmann::json j = progressJson(p);
                   j["error_vs_time"] = errorSeriesJson(p);
                   j["settings"] = {{"algorithm", algorithmName(p.settings.algorithm)},
                                    {"width", p.width},
                                    {"height", p.height},
                                    {"seed", p.settings.seed},
                                    {"samples_per_pixel", p.settings.samplesPerPixel},
                                    {"mutations_per_pixel", p.settings.mutationsPerPixel},
                                    {"time_budget_seconds", p.settings.timeBudgetSeconds},
                                    {"num_chains", p.settings.numChains}};
                   json(r, j);
                 });
    server_->Get(R"(/api/jobs/([A-Za-z0-9_-]{1,64})/preview\.png)",
                 [this](const httplib::Request& q, httplib::Response& r) {
                   if (!allowed(q, r)) return;
                   std::string png;
                   Status s;
                   if (!preview(q.matches[1], &png, &s)) return fail(r, s);
                   r.set_header("Cache-Control", "no-store");
                   r.set_content(png, "image/png");
                 });
    server_->Get("/api/workers", [this](const httplib::Request& q, httplib::Response& r) {
      if (!allowed(q, r)) return;
      json(r, workersJson());
    });
    server_->Get("/metrics", [this](const httplib::Request& q, httplib::Response& r) {
      if (!allowed(q, r)) return;
      r.set_content(metrics(), "text/plain; version=0.0.4");
    });
  }

  Coordinator* coordinator_;
  const CallGuard* guard_;
  std::unique_ptr<httplib::Server> server_;  // an httplib::SSLServer with TLS
  std::thread thread_;
  int port_ = 0;
  bool https_ = false;
};

}  // namespace

std::unique_ptr<HttpService> HttpService::start(const std::string& address,
                                                Coordinator* coordinator, const CallGuard* guard,
                                                const ServerSecurity& security,
                                                std::string* error) {
  auto service = std::make_unique<HttplibService>(coordinator, guard);
  if (!service->start(address, security, error)) return nullptr;
  return service;
}

}  // namespace farm
