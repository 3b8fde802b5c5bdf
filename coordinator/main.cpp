// farm-coordinator: accepts jobs from `farm submit`, bootstraps them, leases chains to
// farm-worker processes and sums their flushes into the final image.
#include <pthread.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "coordinator/coordinator.h"
#include "coordinator/grpc_service.h"
#include "coordinator/http_service.h"
#include "ops/structured_log.h"

namespace {

std::string makeTempDataDir() {
  std::string pattern =
      (std::filesystem::temp_directory_path() / "farm-coordinator-XXXXXX").string();
  if (!mkdtemp(pattern.data())) return "";
  return pattern;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "farm-coordinator: the render farm's coordinator. Accepts jobs from `farm submit`, runs "
      "each job's bootstrap, leases its chains to farm-worker processes, sums their flushes in "
      "double precision and serves progress and the final EXR. With --data DIR the coordinator "
      "is durable: jobs, plans and every accepted flush are kept in DIR/coordinator.db (SQLite), "
      "and a coordinator started again on DIR - after a crash, a kill or a shutdown - resumes "
      "every job where its last acknowledged flush left it; workers reconnect on their own. "
      "Without --data, job records live in memory only and a restart forgets them."};
  std::string listen;
  std::string dataDir;
  double leaseSeconds = 30;
  app.add_option("--listen", listen,
                 "HOST:PORT to serve the client and worker APIs on (port 0: pick a free port; "
                 "the chosen address is printed on stdout)")
      ->required();
  app.add_option("--data", dataDir,
                 "directory for the job database, uploaded scene files and final images; a "
                 "coordinator started on a directory a previous one used resumes its jobs "
                 "(default: a new directory under the system's temporary directory, and job "
                 "records in memory only)");
  int maxChainFailures = 3;
  app.add_option(
         "--max-chain-failures", maxChainFailures,
         "a worker whose lease of one chain expires (or that sends it a malformed flush) "
         "this many times gets no more chains of that job; the job's status names it. A chain "
         "that has had three workers set aside fails its job")
      ->check(CLI::Range(1, 1000000))
      ->default_str("3");
  int maxJobs = 100;
  app.add_option("--max-jobs", maxJobs,
                 "jobs queued or rendering at once; a submit beyond is refused "
                 "(RESOURCE_EXHAUSTED) until one finishes or is cancelled")
      ->check(CLI::Range(1, 100000))
      ->default_str("100");
  app.add_option("--lease-seconds", leaseSeconds,
                 "how long a chain's lease lives without a flush or renewal before the chain "
                 "goes to another worker")
      ->check(CLI::Range(0.5, 3600.0))
      ->default_str("30");
  farm::ServerSecurity security;
  app.add_option("--tls-cert", security.certFile,
                 "PEM certificate chain to serve TLS with (with --tls-key; clients verify it "
                 "against their --tls-ca, and its names must match the HOST they dial)")
      ->envname("FARM_COORDINATOR_TLS_CERT");
  app.add_option("--tls-key", security.keyFile, "PEM private key of --tls-cert (unencrypted)")
      ->envname("FARM_COORDINATOR_TLS_KEY");
  app.add_option("--tls-client-ca", security.clientCaFile,
                 "PEM CA certificates: with TLS, every caller (worker or client) must present a "
                 "certificate signed by one of them (mutual TLS)")
      ->envname("FARM_COORDINATOR_TLS_CLIENT_CA");
  app.add_option("--submit-token-file", security.submitTokenFile,
                 "file whose first line is the token the client API (submit, status, fetch, "
                 "cancel, list, report) asks for as `authorization: Bearer TOKEN`")
      ->envname("FARM_SUBMIT_TOKEN_FILE");
  app.add_option("--work-token-file", security.workTokenFile,
                 "file whose first line is the token the worker API asks for; it must differ "
                 "from the submit token, and neither opens the other's API")
      ->envname("FARM_WORK_TOKEN_FILE");
  std::string healthListen;
  app.add_option("--health-listen", healthListen,
                 "HOST:PORT for a plaintext listener with only the standard gRPC health service "
                 "(grpc.health.v1), for probes that cannot use TLS or a token (Kubernetes' gRPC "
                 "probes); it serves no jobs, images or tokens");
  std::string http;
  app.add_option("--http", http,
                 "HOST:PORT to serve a live web page on (jobs, a job's preview, error curve, "
                 "settings and plan, the workers) and /metrics in the Prometheus text format; "
                 "read-only, and with a submit token it asks for it (as the password of HTTP "
                 "basic authentication). HTTPS with --tls-cert/--tls-key (the same certificate); "
                 "beyond loopback only with TLS and a submit token, or with --insecure");
  app.add_flag("--insecure", security.insecure,
               "listen on an address other than loopback without TLS or without both tokens "
               "(refused otherwise: anyone who can reach the port could read images and tokens, "
               "submit jobs or pose as a worker)");
  std::string logFormatName = "text";
  farm::addLogFormatOption(&app, &logFormatName);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "farm-coordinator: error: " << e.what() << " (see --help)\n";
    return 2;
  }

  farm::LogFormat logFormat = farm::LogFormat::kText;
  farm::parseLogFormat(logFormatName, &logFormat);
  farm::setUpLogging("farm-coordinator", logFormat);
  // From here on, what ends the process goes to the log too (one JSON object in json mode).
  auto fatal = [&](const std::string& message) {
    return farm::logFatal("farm-coordinator", logFormat, message, 1);
  };

  const bool temporaryDataDir = dataDir.empty();
  if (temporaryDataDir) {
    dataDir = makeTempDataDir();
    if (dataDir.empty()) {
      return fatal("cannot create a data directory under " +
                   std::filesystem::temp_directory_path().string());
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(dataDir, ec);
  if (ec || !std::filesystem::is_directory(dataDir)) {
    return fatal("cannot use data directory '" + dataDir +
                 "': " + (ec ? ec.message() : "not a directory"));
  }

  // SIGINT and SIGTERM are taken by sigwait below; block them before any thread starts so that
  // every thread inherits the mask and none is interrupted.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  farm::CoordinatorOptions options;
  options.dataDir = dataDir;
  options.leaseSeconds = leaseSeconds;
  options.maxChainFailures = maxChainFailures;
  options.maxActiveJobs = maxJobs;
  options.log = [](const std::string& line) { spdlog::info("{}", line); };
  options.durable = !temporaryDataDir;
  if (!options.durable) {
    spdlog::info(
        "job records are kept in memory only: a restart forgets every job (pass --data "
        "DIR to keep them)");
  }
  std::unique_ptr<farm::Coordinator> coordinatorPtr;
  try {
    coordinatorPtr = std::make_unique<farm::Coordinator>(options);
  } catch (const std::exception& e) {
    return fatal(e.what());
  }
  farm::Coordinator& coordinator = *coordinatorPtr;
  std::string error;
  auto server = farm::CoordinatorServer::start(listen, &coordinator, security, &error);
  if (!server) {
    if (temporaryDataDir) std::filesystem::remove_all(dataDir, ec);
    return fatal(error);
  }
  std::string host = listen.substr(0, listen.rfind(':'));
  spdlog::info("serving {}", server->security());
  if (const std::string warning = server->guard()->exposureWarning(); !warning.empty())
    spdlog::warn("{} ({}:{})", warning, host, server->port());
  std::cout << "farm-coordinator listening on " << host << ":" << server->port() << " (data in "
            << dataDir << "; " << server->security() << ")" << std::endl;

  std::unique_ptr<farm::HealthServer> health;
  if (!healthListen.empty()) {
    health = farm::HealthServer::start(healthListen, &error);
    if (!health) {
      server->shutdown();
      return fatal(error);
    }
    std::cout << "farm-coordinator health checks on "
              << healthListen.substr(0, healthListen.rfind(':')) << ":" << health->port()
              << std::endl;
  }
  std::unique_ptr<farm::HttpService> web;
  if (!http.empty()) {
    const bool locked = server->guard()->tls() && server->guard()->asksToken(farm::Role::kSubmit);
    if (!farm::isLoopbackAddress(http) && !locked && !security.insecure) {
      server->shutdown();
      return fatal(
          "refusing to serve the web page on " + http +
          (server->guard()->tls() ? " without a submit token" : " in plaintext (no --tls-cert)") +
          ": anyone on the network could see the jobs and images. Serve it on loopback "
          "(and reach it through an SSH tunnel), give the coordinator TLS and a submit "
          "token, or pass --insecure");
    }
    web = farm::HttpService::start(http, &coordinator, server->guard(), security, &error);
    if (!web) {
      server->shutdown();
      return fatal(error);
    }
    std::cout << "farm-coordinator web page on " << (web->https() ? "https" : "http") << "://"
              << http.substr(0, http.rfind(':')) << ":" << web->port() << "/" << std::endl;
  }

  int signal = 0;
  sigwait(&signals, &signal);
  spdlog::info("{}, shutting down", signal == SIGINT ? "SIGINT" : "SIGTERM");
  if (web) web->stop();
  if (health) health->shutdown();
  server->shutdown();
  return 0;
}
