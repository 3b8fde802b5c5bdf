// The farm across hosts: network namespaces joined by veth pairs stand in for machines (one for
// the coordinator, one per worker host; a worker reaches the coordinator only over its own
// link). Workers join and leave mid-job (two at once on one host, sharing its cache), one is
// killed, one comes back; the image equals `farm render`'s of the same job and seed, and each
// host fetches the scene bundle once. The coordinator listens beyond loopback, so the farm runs
// secured as a user would run it: TLS with client certificates and a token per role.
// Needs root and `ip netns` (iproute2); skipped with the reason where they are missing.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "common/film/image.h"
#include "tests/test_pki.h"
#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

// iproute2's `ip` (deploy/install-deps.sh installs it), or empty.
std::string ipCommand() {
  for (const char* path : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"}) {
    if (::access(path, X_OK) == 0) return path;
  }
  return "";
}

// Namespaces "<prefix>c" (the coordinator's) and "<prefix>w<i>", i = 1..hosts, worker host i
// at 10.77.i.2 reaching the coordinator at 10.77.i.1 over veth pair i. Removed when destroyed.
class HostNetwork {
 public:
  static const std::string& ip() {
    static const std::string path = ipCommand();
    return path;
  }
  HostNetwork(int hosts, const std::string& scratch)
      : prefix_("farm" + std::to_string(::getpid() % 100000)), scratch_(scratch) {
    if (::geteuid() != 0) {
      problem_ = "not root";
      return;
    }
    if (ip().empty()) {
      problem_ = "iproute2's ip is not installed";
      return;
    }
    std::vector<std::vector<std::string>> commands = {
        {"ip", "netns", "add", coordinator()},
        {"ip", "-n", coordinator(), "link", "set", "lo", "up"}};
    for (int i = 1; i <= hosts; ++i) {
      const std::string ns = host(i), a = prefix_ + "a" + std::to_string(i),
                        b = prefix_ + "b" + std::to_string(i), net = "10.77." + std::to_string(i);
      commands.push_back({"ip", "netns", "add", ns});
      commands.push_back({"ip", "-n", ns, "link", "set", "lo", "up"});
      commands.push_back({"ip", "link", "add", a, "type", "veth", "peer", "name", b});
      commands.push_back({"ip", "link", "set", a, "netns", coordinator()});
      commands.push_back({"ip", "link", "set", b, "netns", ns});
      commands.push_back({"ip", "-n", coordinator(), "addr", "add", net + ".1/24", "dev", a});
      commands.push_back({"ip", "-n", coordinator(), "link", "set", a, "up"});
      commands.push_back({"ip", "-n", ns, "addr", "add", net + ".2/24", "dev", b});
      commands.push_back({"ip", "-n", ns, "link", "set", b, "up"});
      hosts_ = i;
    }
    for (auto& command : commands) {
      command[0] = ip();
      CommandResult r = runCommand(command, seconds(20), scratch_);
      if (r.exitCode != 0) {
        problem_ = "`" + join(command) + "` failed: " + r.err;
        return;
      }
    }
  }
  ~HostNetwork() {
    if (ip().empty()) return;
    runCommand({ip(), "netns", "del", coordinator()}, seconds(20), scratch_);
    for (int i = 1; i <= hosts_; ++i) {
      runCommand({ip(), "netns", "del", host(i)}, seconds(20), scratch_);
    }
  }
  const std::string& problem() const { return problem_; }
  std::string coordinator() const { return prefix_ + "c"; }
  std::string host(int i) const { return prefix_ + "w" + std::to_string(i); }
  static std::string coordinatorAddressFrom(int i) { return "10.77." + std::to_string(i) + ".1"; }
  // argv run inside namespace `ns`.
  static std::vector<std::string> in(const std::string& ns, std::vector<std::string> argv) {
    argv.insert(argv.begin(), {ip(), "netns", "exec", ns});
    return argv;
  }

 private:
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : " ") + x;
    return s;
  }
  std::string prefix_, scratch_, problem_;
  int hosts_ = 0;
};

size_t count(const std::string& text, const std::string& needle) {
  size_t n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

TEST(MultiHost, WorkersJoinLeaveAndDieAcrossHostsAndTheImageIsUnchanged) {
  ScratchDir scratch("multi-host");
  HostNetwork net(3, scratch.path());
  if (!net.problem().empty()) GTEST_SKIP() << "no network namespaces here: " << net.problem();

  // The certificate names the address each host dials.
  const TestPki pki =
      makeTestPki(scratch.path(),
                  {"127.0.0.1", HostNetwork::coordinatorAddressFrom(1),
                   HostNetwork::coordinatorAddressFrom(2), HostNetwork::coordinatorAddressFrom(3)});
  ASSERT_EQ(pki.problem, "");
  const std::vector<std::string> clientTls = {"--tls-ca",     pki.caCert,  "--tls-cert",
                                              pki.clientCert, "--tls-key", pki.clientKey};
  ChildProcess coordinator(
      HostNetwork::in(net.coordinator(),
                      {FARM_COORDINATOR_BIN, "--listen", "0.0.0.0:0", "--data",
                       scratch / "coordinator-data", "--lease-seconds", "1.5", "--tls-cert",
                       pki.serverCert, "--tls-key", pki.serverKey, "--tls-client-ca", pki.caCert,
                       "--submit-token-file", pki.submitToken, "--work-token-file", pki.workToken}),
      scratch / "coordinator.out", scratch / "coordinator.err");
  const std::string listening =
      waitForText(scratch / "coordinator.out", "listening on 0.0.0.0:", seconds(15));
  ASSERT_FALSE(listening.empty()) << readFile(scratch / "coordinator.err");
  const std::string port = std::to_string(
      std::atoi(listening.c_str() + listening.find("0.0.0.0:") + std::string("0.0.0.0:").size()));
  auto client = [&](std::vector<std::string> args) {
    args.insert(args.begin() + 1, {"--coordinator", "127.0.0.1:" + port});
    args.insert(args.end(), clientTls.begin(), clientTls.end());
    args.insert(args.end(), {"--token-file", pki.submitToken});
    args.insert(args.begin(), FARM_CLI_BIN);
    return runCommand(HostNetwork::in(net.coordinator(), args), seconds(250), scratch.path());
  };
  // Worker `i` on host `i` (its own cache: a host's disk); `run` numbers its log.
  auto startWorker = [&](int i, int run) {
    const std::string log =
        scratch / ("host" + std::to_string(i) + "-run" + std::to_string(run) + ".log");
    auto w = std::make_unique<ChildProcess>(
        HostNetwork::in(
            net.host(i),
            {FARM_WORKER_BIN, "--coordinator", HostNetwork::coordinatorAddressFrom(i) + ":" + port,
             "--threads", "1", "--cache", scratch / ("cache-host" + std::to_string(i)), "--tls-ca",
             pki.caCert, "--tls-cert", pki.clientCert, "--tls-key", pki.clientKey, "--token-file",
             pki.workToken}),
        log, log);
    EXPECT_FALSE(waitForText(log, "registered", seconds(15)).empty()) << "host " << i << ":\n"
                                                                      << readFile(log);
    return w;
  };
  auto workDone = [&](const std::string& job) -> int64_t {
    CommandResult r = client({"status", job, "--json"});
    const size_t at = r.out.find("\"work_done\": ");
    return r.exitCode != 0 || at == std::string::npos ? -1 : std::atoll(r.out.c_str() + at + 13);
  };
  auto waitForMore = [&](const std::string& job, int64_t than) {
    const auto deadline = std::chrono::steady_clock::now() + seconds(90);
    int64_t done = workDone(job);
    while (done <= than && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      done = workDone(job);
    }
    return done;
  };

  // A worker on another host cannot reach the coordinator's loopback: the hosts are apart.
  CommandResult probe =
      runCommand(HostNetwork::in(net.host(1), {FARM_CLI_BIN, "status", "--coordinator",
                                               "127.0.0.1:" + port, "job-000000000000"}),
                 seconds(30), scratch.path());
  EXPECT_NE(probe.exitCode, 0);

  auto first = startWorker(1, 1);
  auto second = startWorker(2, 1);
  const std::vector<std::string> settings = {
      "--algorithm", "mlt", "--width", "64", "--height", "48", "--seed", "4", "--mpp", "2048"};
  std::vector<std::string> submit = {"submit", kScene};
  submit.insert(submit.end(), settings.begin(), settings.end());
  CommandResult submitted = client(submit);
  ASSERT_EQ(submitted.exitCode, 0) << submitted.err;
  const std::string job = lastLine(submitted.out);
  ASSERT_EQ(job.rfind("job-", 0), 0u) << job;

  int64_t done = waitForMore(job, 0);
  ASSERT_GT(done, 0) << readFile(scratch / "coordinator.err");
  auto third = startWorker(3, 1);  // joins mid-job, two workers on one host
  auto thirdTwin = startWorker(3, 2);
  EXPECT_EQ(first->stop(seconds(20)), 0) << "a worker leaving must exit cleanly";
  done = waitForMore(job, done);
  second->signal(SIGKILL);  // dies mid-job
  EXPECT_EQ(second->wait(seconds(10)), 128 + SIGKILL);
  const int64_t total = int64_t(64) * 48 * 2048;
  EXPECT_LT(done, total) << "the job ended before the worker died";
  auto firstAgain = startWorker(1, 2);  // comes back on its host

  CommandResult fetched =
      client({"fetch", job, "-o", scratch / "distributed.exr", "--timeout", "240"});
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err << "\n" << readFile(scratch / "coordinator.err");
  EXPECT_EQ(third->stop(seconds(20)), 0);
  EXPECT_EQ(thirdTwin->stop(seconds(20)), 0);
  EXPECT_EQ(firstAgain->stop(seconds(20)), 0);

  // Each host fetched the bundle at most once, whatever how often its workers came and went.
  for (int i = 1; i <= 3; ++i) {
    std::string logs = readFile(scratch / ("host" + std::to_string(i) + "-run1.log"));
    if (i != 2) logs += readFile(scratch / ("host" + std::to_string(i) + "-run2.log"));
    EXPECT_LE(count(logs, "fetching scene bundle"), 1u) << "host " << i << ":\n" << logs;
  }
  EXPECT_EQ(count(readFile(scratch / "host1-run2.log"), "fetching scene bundle"), 0u)
      << "host 1 fetched the bundle again";

  std::vector<std::string> render = {FARM_CLI_BIN, "render", kScene, "-o", scratch / "embedded.exr",
                                     "--threads",  "2"};
  render.insert(render.end(), settings.begin(), settings.end());
  CommandResult rendered = runCommand(render, seconds(180), scratch.path());
  ASSERT_EQ(rendered.exitCode, 0) << rendered.err;
  Image distributed, embedded;
  std::string error;
  ASSERT_TRUE(readExr(scratch / "distributed.exr", &distributed, &error)) << error;
  ASSERT_TRUE(readExr(scratch / "embedded.exr", &embedded, &error)) << error;
  ASSERT_EQ(distributed.rgb.size(), embedded.rgb.size());
  double worst = 0;
  for (size_t i = 0; i < embedded.rgb.size(); ++i) {
    ASSERT_TRUE(std::isfinite(distributed.rgb[i]));
    if (std::abs(embedded.rgb[i]) > 1e-3) {
      worst = std::max(worst, double(std::abs(distributed.rgb[i] - embedded.rgb[i]) /
                                     std::abs(embedded.rgb[i])));
    }
  }
  EXPECT_LT(worst, 1e-4);
  EXPECT_EQ(coordinator.stop(), 0);
}

}  // namespace
}  // namespace farm::testing
