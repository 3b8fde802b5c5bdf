#include "tests/test_support.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

namespace farm::testing {
namespace fs = std::filesystem;

ScratchDir::ScratchDir(const std::string& tag) {
  std::string pattern = (fs::temp_directory_path() / ("farm-test-" + tag + "-XXXXXX")).string();
  if (mkdtemp(pattern.data())) path_ = pattern;
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  if (!path_.empty() && !std::getenv("FARM_KEEP_TEST_FILES")) fs::remove_all(path_, ec);
}

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& stdoutPath,
                           const std::string& stderrPath) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_ = fork();
  if (pid_ == 0) {
    int out = open(stdoutPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int err = open(stderrPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int in = open("/dev/null", O_RDONLY);
    if (out < 0 || err < 0 || in < 0) _exit(126);
    dup2(in, 0);
    dup2(out, 1);
    dup2(err, 2);
    // The test runner may block signals; a child must start with the defaults.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ > 0 && !reaped_) {
    kill(pid_, SIGKILL);
    wait(std::chrono::seconds(5));
  }
}

bool ChildProcess::running() {
  return !reaped_ && wait(std::chrono::milliseconds(0)) == -1;
}

int ChildProcess::wait(std::chrono::milliseconds timeout) {
  if (pid_ <= 0) return -1;
  if (reaped_) return status_;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    pid_t r = waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      reaped_ = true;
      status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return status_;
    }
    if (std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void ChildProcess::signal(int sig) {
  if (pid_ > 0 && !reaped_) kill(pid_, sig);
}

int ChildProcess::stop(std::chrono::milliseconds grace) {
  signal(SIGTERM);
  int status = wait(grace);
  if (status == -1) {
    signal(SIGKILL);
    wait(std::chrono::seconds(5));
    return -1;
  }
  return status;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

CommandResult runCommand(const std::vector<std::string>& argv, std::chrono::milliseconds timeout,
                         const std::string& scratch) {
  static std::atomic<int> counter{0};
  const int n = ++counter;
  const std::string out = scratch + "/cmd" + std::to_string(n) + ".out";
  const std::string err = scratch + "/cmd" + std::to_string(n) + ".err";
  CommandResult result;
  {
    ChildProcess child(argv, out, err);
    result.exitCode = child.wait(timeout);
    if (result.exitCode == -1) child.signal(SIGKILL);
  }
  result.out = readFile(out);
  result.err = readFile(err);
  return result;
}

std::string waitForText(const std::string& path, const std::string& needle,
                        std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    std::string text = readFile(path);
    if (text.find(needle) != std::string::npos) return text;
    if (std::chrono::steady_clock::now() >= deadline) return "";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::string lastLine(const std::string& text) {
  std::string t = text;
  while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
  size_t at = t.rfind('\n');
  return at == std::string::npos ? t : t.substr(at + 1);
}

CoordinatorProcess::CoordinatorProcess(const std::string& scratch, double leaseSeconds, int port,
                                       const std::string& tag,
                                       const std::vector<std::string>& extraArgs)
    : scratch_(scratch), tag_(tag) {
  std::vector<std::string> argv{FARM_COORDINATOR_BIN,
                                "--listen",
                                "127.0.0.1:" + std::to_string(port),
                                "--data",
                                scratch + "/coordinator-data",
                                "--lease-seconds",
                                std::to_string(leaseSeconds)};
  argv.insert(argv.end(), extraArgs.begin(), extraArgs.end());
  process_ = std::make_unique<ChildProcess>(argv, scratch + "/" + tag + ".out",
                                            scratch + "/" + tag + ".err");
  std::string text = waitForText(scratch + "/" + tag + ".out",
                                 "listening on 127.0.0.1:", std::chrono::seconds(15));
  size_t at = text.find("127.0.0.1:");
  if (at != std::string::npos) port_ = std::atoi(text.c_str() + at + 10);
}

std::string CoordinatorProcess::log() const {
  return readFile(scratch_ + "/" + tag_ + ".out") + readFile(scratch_ + "/" + tag_ + ".err");
}

}  // namespace farm::testing
