// farm-coordinator --http: the live page in a real browser (Debian's headless chromium) shows a
// submitted job and the workers, the job's preview changes as it renders, the JSON API and
// /metrics carry the same figures, and with a submit token the page asks for it.
#include <gtest/gtest.h>
#include <httplib.h>
#include <unistd.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_pki.h"
#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

std::string chromiumPath() {
  for (const char* path : {"/usr/bin/chromium", "/usr/bin/chromium-browser"}) {
    if (::access(path, X_OK) == 0) return path;
  }
  return "";
}

// The port of the page, from the coordinator's stdout.
int webPort(const std::string& outPath, const std::string& scheme = "http") {
  const std::string line = "web page on " + scheme + "://127.0.0.1:";
  const std::string text = waitForText(outPath, line, seconds(15));
  const size_t at = text.find(line);
  return at == std::string::npos ? 0 : std::atoi(text.c_str() + at + line.size());
}

// chromium, headless, on `url`: its DOM after the page's scripts ran (--dump-dom), or a
// screenshot into `screenshot`.
CommandResult browse(const std::string& url, const std::string& scratch,
                     const std::string& screenshot = "") {
  std::vector<std::string> argv = {chromiumPath(),
                                   "--headless",
                                   "--no-sandbox",
                                   "--disable-gpu",
                                   "--disable-dev-shm-usage",
                                   "--user-data-dir=" + scratch + "/chromium",
                                   "--window-size=900,1400",
                                   "--virtual-time-budget=3000"};
  argv.push_back(screenshot.empty() ? "--dump-dom" : "--screenshot=" + screenshot);
  argv.push_back(url);
  return runCommand(argv, seconds(90), scratch);
}

TEST(WebPage, ShowsAJobAndItsWorkersAndThePreviewChangesAsItRenders) {
  ASSERT_FALSE(chromiumPath().empty()) << "chromium is not installed (deploy/install-deps.sh)";
  ScratchDir scratch("web-page");
  CoordinatorProcess coordinator(scratch.path(), 5, 0, "coordinator", {"--http", "127.0.0.1:0"});
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  const int port = webPort(scratch / "coordinator.out");
  ASSERT_GT(port, 0) << coordinator.log();
  ChildProcess worker({FARM_WORKER_BIN, "--coordinator", coordinator.address(), "--threads", "2",
                       "--cache", scratch / "cache"},
                      scratch / "worker.log", scratch / "worker.log");
  CommandResult submitted = runCommand(
      {FARM_CLI_BIN, "submit", "--coordinator", coordinator.address(), kScene, "--algorithm",
       "pssmlt", "--width", "64", "--height", "48", "--time", "25", "--flush-every", "3000"},
      seconds(60), scratch.path());
  ASSERT_EQ(submitted.exitCode, 0) << submitted.err;
  const std::string job = lastLine(submitted.out);

  httplib::Client http("127.0.0.1", port);
  http.set_read_timeout(30, 0);
  // Rendering, with work accepted.
  nlohmann::json progress;
  for (int i = 0; i < 300; ++i) {
    auto r = http.Get("/api/jobs/" + job);
    ASSERT_TRUE(r) << "no answer from the page";
    ASSERT_EQ(r->status, 200) << r->body;
    progress = nlohmann::json::parse(r->body);
    if (progress["phase"] == "rendering" && progress["work_done"].get<int64_t>() > 0) break;
    std::this_thread::sleep_for(milliseconds(100));
  }
  ASSERT_EQ(progress["phase"], "rendering") << progress.dump();

  // The JSON API and /metrics.
  auto jobs = http.Get("/api/jobs");
  ASSERT_TRUE(jobs && jobs->status == 200);
  EXPECT_NE(jobs->body.find(job), std::string::npos) << jobs->body;
  // The worker, holding chains (at some moment: with a time budget, chains yield at flush
  // boundaries and are leased again, so an instant may find it between leases).
  std::string workersBody;
  nlohmann::json w;
  for (int i = 0; i < 100; ++i) {
    auto workers = http.Get("/api/workers");
    ASSERT_TRUE(workers && workers->status == 200);
    workersBody = workers->body;
    w = nlohmann::json::parse(workersBody);
    ASSERT_EQ(w.size(), 1u) << workersBody;
    if (w[0]["chains"].get<int>() > 0) break;
    std::this_thread::sleep_for(milliseconds(50));
  }
  EXPECT_GT(w[0]["chains"].get<int>(), 0) << workersBody;
  EXPECT_LT(w[0]["last_contact_seconds"].get<double>(), 10.0) << workersBody;
  auto metrics = http.Get("/metrics");
  ASSERT_TRUE(metrics && metrics->status == 200);
  EXPECT_NE(metrics->body.find("farm_jobs{phase=\"rendering\"} 1"), std::string::npos)
      << metrics->body;
  EXPECT_NE(metrics->body.find("farm_job_fraction{job=\"" + job + "\",algorithm=\"pssmlt\"}"),
            std::string::npos)
      << metrics->body;
  EXPECT_NE(metrics->body.find("farm_workers 1"), std::string::npos) << metrics->body;
  EXPECT_NE(metrics->body.find("farm_worker_chains{worker=\""), std::string::npos) << metrics->body;

  // The page in a browser: the job and the worker in the tables.
  const std::string page = "http://127.0.0.1:" + std::to_string(port) + "/";
  CommandResult dom = browse(page, scratch.path());
  ASSERT_EQ(dom.exitCode, 0) << dom.err;
  EXPECT_NE(dom.out.find(job), std::string::npos) << dom.out;
  EXPECT_NE(dom.out.find("rendering"), std::string::npos) << dom.out;
  EXPECT_NE(dom.out.find("<table id=\"workers\">"), std::string::npos) << dom.out;
  EXPECT_NE(dom.out.find(w[0]["id"].get<std::string>()), std::string::npos) << dom.out;
  // The job's view: its preview and error curve; two screenshots a while apart differ, and so
  // do the preview's bytes.
  CommandResult jobDom = browse(page + "#/job/" + job, scratch.path());
  ASSERT_EQ(jobDom.exitCode, 0) << jobDom.err;
  EXPECT_NE(jobDom.out.find("id=\"preview\""), std::string::npos) << jobDom.out;
  EXPECT_NE(jobDom.out.find("/api/jobs/" + job + "/preview.png"), std::string::npos);
  auto before = http.Get("/api/jobs/" + job + "/preview.png");
  ASSERT_TRUE(before && before->status == 200);
  EXPECT_EQ(before->body.substr(1, 3), "PNG");
  CommandResult first = browse(page + "#/job/" + job, scratch.path(), scratch / "first.png");
  ASSERT_EQ(first.exitCode, 0) << first.err;
  std::this_thread::sleep_for(seconds(2));
  CommandResult second = browse(page + "#/job/" + job, scratch.path(), scratch / "second.png");
  ASSERT_EQ(second.exitCode, 0) << second.err;
  const std::string a = readFile(scratch / "first.png"), b = readFile(scratch / "second.png");
  ASSERT_GT(a.size(), 1000u);
  EXPECT_NE(a, b) << "the job's view did not change while it rendered";
  auto after = http.Get("/api/jobs/" + job + "/preview.png");
  ASSERT_TRUE(after && after->status == 200);
  EXPECT_NE(before->body, after->body) << "the preview did not change while the job rendered";
  EXPECT_EQ(http.Get("/api/jobs/job-000000000000/preview.png")->status, 404);

  CommandResult cancelled =
      runCommand({FARM_CLI_BIN, "cancel", "--coordinator", coordinator.address(), job}, seconds(30),
                 scratch.path());
  EXPECT_EQ(cancelled.exitCode, 0) << cancelled.err;
  EXPECT_EQ(worker.stop(seconds(20)), 0);
  EXPECT_EQ(coordinator.process().stop(), 0);
}

TEST(WebPage, AsksForTheSubmitTokenAndServesOnlyLoopbackWithoutInsecure) {
  ScratchDir scratch("web-token");
  const TestPki pki = makeTestPki(scratch.path());
  ASSERT_EQ(pki.problem, "");
  CoordinatorProcess coordinator(scratch.path(), 5, 0, "coordinator",
                                 {"--http", "127.0.0.1:0", "--submit-token-file", pki.submitToken,
                                  "--work-token-file", pki.workToken});
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  const int port = webPort(scratch / "coordinator.out");
  ASSERT_GT(port, 0) << coordinator.log();
  httplib::Client http("127.0.0.1", port);
  for (const char* path : {"/", "/api/jobs", "/metrics"}) {
    auto none = http.Get(path);
    ASSERT_TRUE(none);
    EXPECT_EQ(none->status, 401) << path;
    EXPECT_TRUE(none->has_header("WWW-Authenticate")) << path;
  }
  const std::string submitToken = lastLine(readFile(pki.submitToken));
  const std::string workToken = lastLine(readFile(pki.workToken));
  http.set_basic_auth("farm", workToken.c_str());
  EXPECT_EQ(http.Get("/api/jobs")->status, 403) << "the work token opens no page";
  http.set_basic_auth("farm", "not-the-token-at-all");
  EXPECT_EQ(http.Get("/api/jobs")->status, 401);
  http.set_basic_auth("farm", submitToken.c_str());
  auto ok = http.Get("/");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  EXPECT_NE(ok->body.find("<title>farm</title>"), std::string::npos);
  httplib::Client bearer("127.0.0.1", port);
  bearer.set_bearer_token_auth(submitToken.c_str());
  EXPECT_EQ(bearer.Get("/metrics")->status, 200);

  CommandResult exposed =
      runCommand({FARM_COORDINATOR_BIN, "--listen", "127.0.0.1:0", "--http", "0.0.0.0:0"},
                 seconds(20), scratch.path());
  EXPECT_EQ(exposed.exitCode, 1);
  EXPECT_NE(exposed.err.find("refusing to serve the web page on 0.0.0.0:0"), std::string::npos)
      << exposed.err;
}

// With TLS the page is HTTPS, with the coordinator's certificate: a client that trusts our CA
// gets it (with the token), plaintext HTTP gets nothing, a client that trusts another CA refuses
// the certificate. TLS and a submit token let the page listen beyond loopback.
TEST(WebPage, ServesHttpsWithTheCoordinatorsCertificate) {
  ScratchDir scratch("web-https");
  const TestPki pki = makeTestPki(scratch.path());
  ASSERT_EQ(pki.problem, "");
  const std::vector<std::string> tls = {"--tls-cert",        pki.serverCert,        "--tls-key",
                                        pki.serverKey,       "--submit-token-file", pki.submitToken,
                                        "--work-token-file", pki.workToken};
  std::vector<std::string> args = tls;
  args.insert(args.end(), {"--http", "127.0.0.1:0"});
  CoordinatorProcess coordinator(scratch.path(), 5, 0, "coordinator", args);
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  const int port = webPort(scratch / "coordinator.out", "https");
  ASSERT_GT(port, 0) << coordinator.log();
  const std::string submitToken = lastLine(readFile(pki.submitToken));

  httplib::SSLClient https("localhost", port);
  https.set_ca_cert_path(pki.caCert.c_str());
  https.enable_server_certificate_verification(true);
  https.set_bearer_token_auth(submitToken.c_str());
  auto page = https.Get("/");
  ASSERT_TRUE(page) << httplib::to_string(page.error());
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<title>farm</title>"), std::string::npos);
  auto metrics = https.Get("/metrics");
  ASSERT_TRUE(metrics);
  EXPECT_EQ(metrics->status, 200);
  httplib::SSLClient anonymous("localhost", port);
  anonymous.set_ca_cert_path(pki.caCert.c_str());
  anonymous.enable_server_certificate_verification(true);
  auto refused = anonymous.Get("/api/jobs");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 401) << "TLS does not stand in for the token";

  httplib::Client plain("127.0.0.1", port);
  plain.set_read_timeout(5, 0);
  plain.set_bearer_token_auth(submitToken.c_str());
  auto cleartext = plain.Get("/api/jobs");
  EXPECT_FALSE(cleartext && cleartext->status == 200) << "the page answered in plaintext";

  httplib::SSLClient distrusting("localhost", port);
  distrusting.set_ca_cert_path(pki.rogueCert.c_str());
  distrusting.enable_server_certificate_verification(true);
  distrusting.set_bearer_token_auth(submitToken.c_str());
  auto unverified = distrusting.Get("/api/jobs");
  EXPECT_FALSE(unverified) << "a certificate our CA did not sign was accepted";
  EXPECT_EQ(coordinator.process().stop(), 0);

  // Beyond loopback: TLS and a submit token are enough; TLS without the token is not.
  args = tls;
  args.insert(args.end(), {"--listen", "127.0.0.1:0", "--http", "0.0.0.0:0"});
  args.insert(args.begin(), FARM_COORDINATOR_BIN);
  ChildProcess exposed(args, scratch / "exposed.out", scratch / "exposed.err");
  EXPECT_NE(waitForText(scratch / "exposed.out", "web page on https://0.0.0.0:", seconds(15))
                .find("https://0.0.0.0:"),
            std::string::npos)
      << readFile(scratch / "exposed.err");
  EXPECT_EQ(exposed.stop(seconds(20)), 0);
  CommandResult tokenless =
      runCommand({FARM_COORDINATOR_BIN, "--listen", "127.0.0.1:0", "--tls-cert", pki.serverCert,
                  "--tls-key", pki.serverKey, "--http", "0.0.0.0:0"},
                 seconds(20), scratch.path());
  EXPECT_EQ(tokenless.exitCode, 1);
  EXPECT_NE(tokenless.err.find("without a submit token"), std::string::npos) << tokenless.err;
}

}  // namespace
}  // namespace farm::testing
