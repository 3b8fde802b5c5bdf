// A secured farm with real processes and real certificates (made by the openssl command): a
// coordinator serving TLS, optionally mutual, with a token per role; a worker and the CLI that
// present them; and each wrong caller refused with its status - plaintext against TLS, a CA that
// did not sign the coordinator, a client certificate from the wrong CA, no token, a wrong token,
// the other role's token. The exact gRPC codes are checked with stubs over the same channels
// the farm's programs build (proto/transport_security.h).
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cmath>
#include <future>
#include <string>
#include <vector>

#include "common/film/image.h"
#include "proto/farm.grpc.pb.h"
#include "proto/transport_security.h"
#include "proto/wire_limits.h"
#include "tests/test_pki.h"
#include "tests/test_support.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

const std::string kScene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";

// A channel with `security`, as the farm's programs build it.
std::shared_ptr<grpc::Channel> channelWith(const std::string& address,
                                           const ClientSecurity& security) {
  std::string error;
  auto channel = makeClientChannel(address, security, grpc::ChannelArguments(), &error);
  EXPECT_TRUE(channel) << error;
  return channel;
}

// The status of one call, and its message in *message.
grpc::StatusCode outcome(const grpc::Status& s, std::string* message) {
  if (message) *message = s.error_message();
  return s.error_code();
}

// ListJobs (client API) over a channel with `security`.
grpc::StatusCode listJobs(const std::string& address, const ClientSecurity& security,
                          std::string* message = nullptr) {
  auto channel = channelWith(address, security);
  if (!channel) return grpc::StatusCode::UNKNOWN;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + seconds(5));
  v1::ListJobsResponse response;
  return outcome(
      v1::ClientApi::NewStub(channel)->ListJobs(&context, v1::ListJobsRequest(), &response),
      message);
}

// RegisterWorker (worker API) over a channel with `security`.
grpc::StatusCode registerWorker(const std::string& address, const ClientSecurity& security,
                                std::string* message = nullptr) {
  auto channel = channelWith(address, security);
  if (!channel) return grpc::StatusCode::UNKNOWN;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + seconds(5));
  v1::RegisterWorkerRequest request;
  request.set_protocol_version(kProtocolVersion);
  request.set_threads(1);
  request.set_host("secure-farm-test");
  request.add_capabilities("pt");
  v1::RegisterWorkerResponse response;
  return outcome(v1::WorkerApi::NewStub(channel)->RegisterWorker(&context, request, &response),
                 message);
}

// grpc.health.v1.Health/Check in plaintext: the answer's bytes (08 01 is SERVING), or the
// status's code.
std::string healthCheck(const std::string& address) {
  auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + seconds(5));
  grpc::Slice empty("", 0);
  grpc::ByteBuffer request(&empty, 1), response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status s) { done.set_value(s); });
  grpc::Status status = done.get_future().get();
  if (!status.ok()) return "status " + std::to_string(int(status.error_code()));
  std::vector<grpc::Slice> slices;
  std::string bytes;
  if (response.Dump(&slices).ok()) {
    for (const grpc::Slice& slice : slices) {
      bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
    }
  }
  return bytes;
}

std::vector<std::string> tlsArgs(const ClientSecurity& s) {
  std::vector<std::string> args;
  if (!s.caFile.empty()) args.insert(args.end(), {"--tls-ca", s.caFile});
  if (!s.certFile.empty())
    args.insert(args.end(), {"--tls-cert", s.certFile, "--tls-key", s.keyFile});
  if (!s.tokenFile.empty()) args.insert(args.end(), {"--token-file", s.tokenFile});
  return args;
}

CommandResult farmCli(std::vector<std::string> args, const std::string& address,
                      const ClientSecurity& security, const std::string& scratch) {
  args.insert(args.begin() + 1, {"--coordinator", address});
  const std::vector<std::string> flags = tlsArgs(security);
  args.insert(args.end(), flags.begin(), flags.end());
  args.insert(args.begin(), FARM_CLI_BIN);
  return runCommand(args, seconds(120), scratch);
}

TEST(SecureFarm, TlsAndTokensRenderAJobAndRefuseEveryWrongCaller) {
  ScratchDir scratch("secure-tls");
  const TestPki pki = makeTestPki(scratch.path());
  ASSERT_EQ(pki.problem, "");
  CoordinatorProcess coordinator(
      scratch.path(), 5, 0, "coordinator",
      {"--tls-cert", pki.serverCert, "--tls-key", pki.serverKey, "--submit-token-file",
       pki.submitToken, "--work-token-file", pki.workToken, "--health-listen", "127.0.0.1:0"});
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  EXPECT_NE(coordinator.log().find("TLS; tokens for submit and work"), std::string::npos)
      << coordinator.log();
  const std::string address = coordinator.address();

  // Probes that speak neither TLS nor tokens get the health service, and nothing else.
  const std::string healthLine =
      waitForText(scratch / "coordinator.out", "health checks on 127.0.0.1:", seconds(10));
  const size_t at = healthLine.find("health checks on 127.0.0.1:");
  ASSERT_NE(at, std::string::npos) << coordinator.log();
  const std::string health = "127.0.0.1:" + std::to_string(std::atoi(healthLine.c_str() + at + 27));
  EXPECT_EQ(healthCheck(health), std::string("\x08\x01", 2)) << "SERVING in plaintext";
  EXPECT_EQ(listJobs(health, {"", "", "", pki.submitToken}), grpc::StatusCode::UNIMPLEMENTED)
      << "the health listener must serve no job API";

  const ClientSecurity submit{pki.caCert, "", "", pki.submitToken};
  const ClientSecurity work{pki.caCert, "", "", pki.workToken};
  std::string message;

  // The right role's token opens its API, and only that one.
  EXPECT_EQ(listJobs(address, submit), grpc::StatusCode::OK);
  EXPECT_EQ(registerWorker(address, work), grpc::StatusCode::OK);
  EXPECT_EQ(listJobs(address, work, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(message.find("needs the submit token"), std::string::npos) << message;
  EXPECT_EQ(registerWorker(address, submit, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(message.find("needs the work token"), std::string::npos) << message;
  // No token, or one that is neither.
  EXPECT_EQ(listJobs(address, {pki.caCert, "", "", ""}, &message),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(message.find("carried none"), std::string::npos) << message;
  EXPECT_EQ(registerWorker(address, {pki.caCert, "", "", ""}), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(listJobs(address, {pki.caCert, "", "", pki.wrongToken}),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(registerWorker(address, {pki.caCert, "", "", pki.wrongToken}),
            grpc::StatusCode::UNAUTHENTICATED);
  // Plaintext against TLS, and a CA that did not sign the coordinator: no connection at all.
  EXPECT_EQ(listJobs(address, {"", "", "", pki.submitToken}), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(listJobs(address, {pki.rogueCert, "", "", pki.submitToken}),
            grpc::StatusCode::UNAVAILABLE);

  // The CLI says which: the other role's token, and plaintext against TLS.
  CommandResult wrongRole = farmCli({"list"}, address, work, scratch.path());
  EXPECT_NE(wrongRole.exitCode, 0);
  EXPECT_NE(wrongRole.err.find("does not open the client API"), std::string::npos) << wrongRole.err;
  CommandResult plaintext =
      farmCli({"list"}, address, {"", "", "", pki.submitToken}, scratch.path());
  EXPECT_NE(plaintext.exitCode, 0);
  EXPECT_NE(plaintext.err.find("pass --tls-ca"), std::string::npos) << plaintext.err;
  // A worker with the submit token is refused at registration and exits, saying why.
  CommandResult refusedWorker = runCommand(
      {FARM_WORKER_BIN, "--coordinator", address, "--threads", "1", "--cache",
       scratch / "cache-refused", "--tls-ca", pki.caCert, "--token-file", pki.submitToken},
      seconds(30), scratch.path());
  EXPECT_NE(refusedWorker.exitCode, 0);
  EXPECT_NE(refusedWorker.err.find("does not open the worker API"), std::string::npos)
      << refusedWorker.err;

  // A whole job over TLS: a worker with the work token, the CLI with the submit token.
  ChildProcess worker(
      {FARM_WORKER_BIN, "--coordinator", "localhost:" + address.substr(10), "--threads", "2",
       "--cache", scratch / "cache", "--tls-ca", pki.caCert, "--token-file", pki.workToken},
      scratch / "worker.log", scratch / "worker.log");
  CommandResult submitted = farmCli({"submit", kScene, "--algorithm", "pssmlt", "--width", "48",
                                     "--height", "32", "--mpp", "64", "--seed", "3"},
                                    address, submit, scratch.path());
  ASSERT_EQ(submitted.exitCode, 0) << submitted.err;
  const std::string job = lastLine(submitted.out);
  CommandResult fetched = farmCli({"fetch", job, "-o", scratch / "secure.exr", "--timeout", "90"},
                                  address, submit, scratch.path());
  ASSERT_EQ(fetched.exitCode, 0) << fetched.err << readFile(scratch / "worker.log");
  EXPECT_EQ(worker.stop(seconds(20)), 0);
  Image image;
  std::string error;
  ASSERT_TRUE(readExr(scratch / "secure.exr", &image, &error)) << error;
  ASSERT_EQ(image.width, 48);
  ASSERT_EQ(image.height, 32);
  double sum = 0;
  for (float v : image.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    sum += v;
  }
  EXPECT_GT(sum, 0.0) << "the job rendered nothing";
  EXPECT_EQ(coordinator.process().stop(), 0) << "the coordinator must survive every refusal";
}

TEST(SecureFarm, MutualTlsAdmitsOnlyCertificatesFromTheClientCa) {
  ScratchDir scratch("secure-mtls");
  const TestPki pki = makeTestPki(scratch.path());
  ASSERT_EQ(pki.problem, "");
  CoordinatorProcess coordinator(
      scratch.path(), 5, 0, "coordinator",
      {"--tls-cert", pki.serverCert, "--tls-key", pki.serverKey, "--tls-client-ca", pki.caCert});
  ASSERT_TRUE(coordinator.ok()) << coordinator.log();
  EXPECT_NE(coordinator.log().find("TLS with client certificates"), std::string::npos);
  const std::string address = coordinator.address();

  EXPECT_EQ(registerWorker(address, {pki.caCert, "", "", ""}), grpc::StatusCode::UNAVAILABLE)
      << "no client certificate";
  EXPECT_EQ(registerWorker(address, {pki.caCert, pki.rogueCert, pki.rogueKey, ""}),
            grpc::StatusCode::UNAVAILABLE)
      << "a certificate the client CA did not sign";
  EXPECT_EQ(listJobs(address, {pki.caCert, pki.rogueCert, pki.rogueKey, ""}),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(registerWorker(address, {pki.caCert, pki.clientCert, pki.clientKey, ""}),
            grpc::StatusCode::OK);
  EXPECT_EQ(listJobs(address, {pki.caCert, pki.clientCert, pki.clientKey, ""}),
            grpc::StatusCode::OK);

  // A real worker with its certificate registers; the CLI with one lists.
  ChildProcess worker(
      {FARM_WORKER_BIN, "--coordinator", address, "--threads", "1", "--cache", scratch / "cache",
       "--tls-ca", pki.caCert, "--tls-cert", pki.clientCert, "--tls-key", pki.clientKey},
      scratch / "worker.log", scratch / "worker.log");
  EXPECT_FALSE(waitForText(scratch / "worker.log", "registered", seconds(15)).empty())
      << readFile(scratch / "worker.log");
  EXPECT_EQ(worker.stop(seconds(20)), 0);
  CommandResult listed =
      farmCli({"list"}, address, {pki.caCert, pki.clientCert, pki.clientKey, ""}, scratch.path());
  EXPECT_EQ(listed.exitCode, 0) << listed.err;
  // A key that is not the certificate's is caught before any connection, naming the file.
  CommandResult mismatched =
      farmCli({"list"}, address, {pki.caCert, pki.clientCert, pki.rogueKey, ""}, scratch.path());
  EXPECT_NE(mismatched.exitCode, 0);
  EXPECT_NE(mismatched.err.find("does not belong to certificate"), std::string::npos)
      << mismatched.err;
  EXPECT_EQ(coordinator.process().stop(), 0);
}

TEST(SecureFarm, AListenerBeyondLoopbackNeedsTlsAndBothTokensOrInsecure) {
  ScratchDir scratch("secure-exposed");
  const TestPki pki = makeTestPki(scratch.path());
  ASSERT_EQ(pki.problem, "");
  auto start = [&](std::vector<std::string> flags) {
    flags.insert(flags.begin(), {FARM_COORDINATOR_BIN, "--listen", "0.0.0.0:0"});
    return runCommand(flags, seconds(20), scratch.path());
  };
  const std::vector<std::string> tls = {"--tls-cert", pki.serverCert, "--tls-key", pki.serverKey};

  CommandResult plaintext = start({});
  EXPECT_EQ(plaintext.exitCode, 1);
  EXPECT_NE(plaintext.err.find("refusing to listen on 0.0.0.0:0 in plaintext"), std::string::npos)
      << plaintext.err;
  std::vector<std::string> oneToken = tls;
  oneToken.insert(oneToken.end(), {"--work-token-file", pki.workToken});
  CommandResult tokenless = start(oneToken);
  EXPECT_EQ(tokenless.exitCode, 1);
  EXPECT_NE(tokenless.err.find("without --submit-token-file"), std::string::npos) << tokenless.err;
  std::vector<std::string> sameTokens = tls;
  sameTokens.insert(sameTokens.end(),
                    {"--submit-token-file", pki.workToken, "--work-token-file", pki.workToken});
  CommandResult same = start(sameTokens);
  EXPECT_EQ(same.exitCode, 1);
  EXPECT_NE(same.err.find("tokens are the same"), std::string::npos) << same.err;
  CommandResult missing =
      start({"--tls-cert", scratch / "nowhere.pem", "--tls-key", pki.serverKey});
  EXPECT_EQ(missing.exitCode, 1);
  EXPECT_NE(missing.err.find("cannot read certificate"), std::string::npos) << missing.err;

  // With TLS and both tokens it serves; with --insecure it serves plaintext and warns.
  std::vector<std::string> full = tls;
  full.insert(full.end(),
              {"--submit-token-file", pki.submitToken, "--work-token-file", pki.workToken});
  full.insert(full.begin(), {FARM_COORDINATOR_BIN, "--listen", "0.0.0.0:0"});
  {
    ChildProcess secured(full, scratch / "secured.out", scratch / "secured.err");
    EXPECT_FALSE(
        waitForText(scratch / "secured.out", "TLS; tokens for submit and work", seconds(15))
            .empty())
        << readFile(scratch / "secured.err");
    EXPECT_EQ(secured.stop(), 0);
  }
  {
    ChildProcess insecure({FARM_COORDINATOR_BIN, "--listen", "0.0.0.0:0", "--insecure"},
                          scratch / "insecure.out", scratch / "insecure.err");
    EXPECT_FALSE(waitForText(scratch / "insecure.err", "readable", seconds(15)).empty())
        << readFile(scratch / "insecure.err");
    EXPECT_EQ(insecure.stop(), 0);
  }
  // On loopback plaintext needs nothing, and says so.
  CoordinatorProcess loopback(scratch.path(), 5, 0, "loopback");
  ASSERT_TRUE(loopback.ok()) << loopback.log();
  EXPECT_NE(loopback.log().find("plaintext (loopback only); no tokens"), std::string::npos)
      << loopback.log();
}

}  // namespace
}  // namespace farm::testing
