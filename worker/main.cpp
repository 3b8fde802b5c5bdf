// farm-worker: runs chains for a farm-coordinator with all (or --threads) hardware threads.
#include <pthread.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <thread>

#include "ops/client_security_options.h"
#include "ops/structured_log.h"
#include "worker/remote_chain_source.h"
#include "worker/worker_pool.h"

namespace {

std::string defaultCacheDir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    return std::string(xdg) + "/farm-worker";
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    return std::string(home) + "/.cache/farm-worker";
  }
  return (std::filesystem::temp_directory_path() / ("farm-worker-" + std::to_string(getuid())))
      .string();
}

}  // namespace

int main(int argc, char** argv) {
  const int hardwareThreads = int(std::max(1u, std::thread::hardware_concurrency()));
  CLI::App app{
      "farm-worker: leases chains from a farm-coordinator, runs each on a thread of its own, "
      "and uploads every flush (those of one job summed into one upload, see --batch-window). "
      "Scene bundles are fetched once per content hash and cached. "
      "Retries with backoff while the coordinator is unreachable; SIGINT or SIGTERM stops the "
      "chains at their next flush and exits."};
  std::string coordinator;
  int threads = hardwareThreads;
  std::string cacheDir = defaultCacheDir();
  app.add_option("--coordinator", coordinator, "HOST:PORT of the farm-coordinator")->required();
  app.add_option("--threads", threads, "chains to run at once (default: all hardware threads)")
      ->check(CLI::Range(1, 4096))
      ->default_str(std::to_string(hardwareThreads));
  app.add_option("--cache", cacheDir, "directory for cached scene bundles")->default_str(cacheDir);
  double batchWindow = 1;
  app.add_option("--batch-window", batchWindow,
                 "sum the flushes of this worker's chains of one job into one upload, sent once "
                 "every such chain has flushed or this many seconds after the first did; 0 "
                 "uploads each flush on its own")
      ->check(CLI::Range(0.0, 600.0))
      ->default_str("1");
  farm::ClientSecurity security;
  farm::addClientSecurityOptions(&app, &security, "FARM_WORKER", farm::Role::kWork);
  std::string logFormatName = "text";
  farm::addLogFormatOption(&app, &logFormatName);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "farm-worker: error: " << e.what() << " (see --help)\n";
    return 2;
  }

  // Signals are taken by sigtimedwait below; block them before any thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  farm::LogFormat logFormat = farm::LogFormat::kText;
  farm::parseLogFormat(logFormatName, &logFormat);
  farm::setUpLogging("farm-worker", logFormat);
  auto fatal = [&](const std::string& message, int code) {
    return farm::logFatal("farm-worker", logFormat, message, code);
  };
  auto log = [](const std::string& line) { spdlog::info("{}", line); };

  farm::RemoteSourceOptions options;
  options.coordinator = coordinator;
  options.security = security;
  options.threads = threads;
  options.cacheDir = cacheDir;
  options.log = log;
  options.batchWindowSeconds = batchWindow;
  std::unique_ptr<farm::RemoteChainSource> sourcePtr;
  try {
    sourcePtr = std::make_unique<farm::RemoteChainSource>(options);
  } catch (const std::invalid_argument& e) {
    return fatal(e.what(), 2);
  }
  farm::RemoteChainSource& source = *sourcePtr;
  farm::WorkerPoolOptions poolOptions;
  poolOptions.threads = threads;
  poolOptions.log = log;
  farm::WorkerPool pool(&source, poolOptions);

  std::string refused;
  std::atomic<bool> poolEnded{false};
  std::thread runner([&] {
    try {
      pool.run();
    } catch (const std::exception& e) {
      refused = e.what();
    }
    poolEnded = true;
  });

  log("working for " + coordinator + " with " + std::to_string(threads) + " threads");
  const timespec step{0, 200 * 1000 * 1000};
  while (!poolEnded) {
    int signal = sigtimedwait(&signals, nullptr, &step);
    if (signal == SIGINT || signal == SIGTERM) {
      log(std::string(signal == SIGINT ? "SIGINT" : "SIGTERM") +
          ": stopping chains at their next flush");
      pool.stop();
      break;
    }
  }
  runner.join();
  const farm::WorkerPoolStats stats = pool.stats();
  char streaming[160];
  std::snprintf(streaming, sizeof streaming,
                "; streaming flushes took %.2f s of %.2f s of chain time (%.1f%%)",
                stats.uploadSeconds, stats.chainSeconds,
                stats.chainSeconds > 0 ? 100.0 * stats.uploadSeconds / stats.chainSeconds : 0.0);
  const farm::FlushBatcher::Stats batches = source.batchStats();
  const std::string uploads =
      batches.batches > 0 ? " in " + std::to_string(batches.batches) + " uploads" : "";
  log("done: " + std::to_string(stats.chainsStarted) + " chains run, " +
      std::to_string(stats.flushesAccepted) + " flushes accepted" + uploads + streaming);
  if (!refused.empty()) {
    return fatal(refused, 1);
  }
  return 0;
}
