#pragma once
// Helpers for tests that run the farm's real executables: child processes with timeouts,
// scratch directories, and a coordinator started on a free loopback port.
#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace farm::testing {

// A scratch directory, removed with everything in it when the object dies.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// A child process whose stdout and stderr go to files. Killed (SIGKILL) if still running when
// the object dies, so a failing test never leaves processes behind.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& stdoutPath,
               const std::string& stderrPath);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  bool running();
  // The exit status (128 + signal if killed by one), or -1 if it did not end in time.
  int wait(std::chrono::milliseconds timeout);
  void signal(int sig);
  // SIGTERM, then SIGKILL if it does not end within `grace`; returns the exit status.
  int stop(std::chrono::milliseconds grace = std::chrono::seconds(5));

 private:
  pid_t pid_ = -1;
  int status_ = -1;
  bool reaped_ = false;
};

struct CommandResult {
  int exitCode = -1;  // -1: timed out (and killed)
  std::string out, err;
};
// Runs a command to completion (or kills it after `timeout`), capturing its output.
CommandResult runCommand(const std::vector<std::string>& argv, std::chrono::milliseconds timeout,
                         const std::string& scratch);

std::string readFile(const std::string& path);
// Waits until `path` contains `needle`; returns the contents (empty on timeout).
std::string waitForText(const std::string& path, const std::string& needle,
                        std::chrono::milliseconds timeout);
std::string lastLine(const std::string& text);

// A farm-coordinator on 127.0.0.1 with a port of its own choosing (or `port`), its data in
// scratch/coordinator-data (durable: another one started on the same scratch resumes its jobs)
// and its output in scratch/<tag>.out and .err.
class CoordinatorProcess {
 public:
  // `extraArgs` go on its command line (TLS and token flags, for example).
  CoordinatorProcess(const std::string& scratch, double leaseSeconds = 5, int port = 0,
                     const std::string& tag = "coordinator",
                     const std::vector<std::string>& extraArgs = {});
  bool ok() const { return port_ > 0; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  ChildProcess& process() { return *process_; }
  std::string log() const;

 private:
  std::string scratch_, tag_;
  std::unique_ptr<ChildProcess> process_;
  int port_ = 0;
};

}  // namespace farm::testing
