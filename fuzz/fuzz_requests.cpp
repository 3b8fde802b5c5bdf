// Every request the coordinator accepts, from hostile bytes, against a real coordinator and its
// gRPC services on loopback: the first byte picks the method, the rest is the request. Unary
// requests travel as the raw bytes (the server decodes them, malformed or not); streamed ones
// as a sequence of [2-byte little-endian length][message] parsed here. The job id "JOB0" and
// the worker id "WKR0" in a request are replaced by those of a real job and worker the target
// made at start, so that inputs get past the id checks into the handlers.
//
// The answers are not checked here (a refusal is the expected answer): the findings are
// crashes, sanitizer reports and leaks, and a coordinator that stops answering.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "coordinator/coordinator.h"
#include "coordinator/grpc_service.h"
#include "fuzz/fuzz_target.h"
#include "proto/farm.grpc.pb.h"

namespace {

using namespace farm;

constexpr auto kCallTimeout = std::chrono::milliseconds(500);

struct Farm {
  std::string dataDir;
  std::unique_ptr<Coordinator> coordinator;
  std::unique_ptr<CoordinatorServer> server;
  std::shared_ptr<grpc::Channel> channel;
  std::string jobId, workerId;
};

Farm& farmUnderTest() {
  static Farm* farm = [] {
    auto* f = new Farm;
    char pattern[] = "/tmp/farm-fuzz-requests-XXXXXX";
    f->dataDir = mkdtemp(pattern) ? pattern : "/tmp";
    CoordinatorOptions options;
    options.dataDir = f->dataDir;
    options.leaseSeconds = 5;
    f->coordinator = std::make_unique<Coordinator>(options);
    std::string error;
    f->server = CoordinatorServer::start("127.0.0.1:0", f->coordinator.get(), &error);
    if (!f->server) {
      std::fprintf(stderr, "fuzz_requests: %s\n", error.c_str());
      std::abort();
    }
    f->channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(f->server->port()),
                                     grpc::InsecureChannelCredentials());
    // A real worker and a real (small) job, for requests to name.
    WorkerInfo info;
    info.threads = 1;
    info.host = "fuzz";
    info.capabilities = {Algorithm::PathTracing, Algorithm::PSSMLT};
    f->coordinator->registerWorker(info, &f->workerId);
    JobSpec spec;
    spec.settings.algorithm = Algorithm::PathTracing;
    spec.settings.width = 8;
    spec.settings.height = 8;
    spec.settings.samplesPerPixel = 1 << 20;
    spec.scenePath = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";
    f->coordinator->submit(spec, &f->jobId);
    // At exit: stop serving, end the coordinator's threads, remove its data.
    std::atexit([] {
      Farm& farm = farmUnderTest();
      farm.channel.reset();
      farm.server->shutdown();
      farm.server.reset();
      farm.coordinator.reset();
      std::filesystem::remove_all(farm.dataDir);
    });
    return f;
  }();
  return *farm;
}

// "JOB0" and "WKR0" become the real ids, in messages that have such fields (C++17: overloads
// picked by whether the field exists).
template <typename M>
auto substituteJob(M* m, int) -> decltype(m->job_id(), void()) {
  if (m->job_id() == "JOB0") m->set_job_id(farmUnderTest().jobId);
}
template <typename M>
void substituteJob(M*, long) {}
template <typename M>
auto substituteWorker(M* m, int) -> decltype(m->worker_id(), void()) {
  if (m->worker_id() == "WKR0") m->set_worker_id(farmUnderTest().workerId);
}
template <typename M>
void substituteWorker(M*, long) {}
template <typename M>
void substituteIds(M* m) {
  substituteJob(m, 0);
  substituteWorker(m, 0);
}
template <typename M>
auto substituteHeader(M* m, int) -> decltype(m->mutable_header(), void()) {
  if (m->has_header()) substituteIds(m->mutable_header());
}
template <typename M>
void substituteHeader(M*, long) {}

// The next [length][bytes] of a stream, or false at its end.
bool nextPart(const uint8_t*& data, size_t& size, std::string* part) {
  if (size < 2) return false;
  const size_t length = size_t(data[0]) | size_t(data[1]) << 8;
  data += 2;
  size -= 2;
  const size_t n = std::min(length, size);
  part->assign(reinterpret_cast<const char*>(data), n);
  data += n;
  size -= n;
  return true;
}

void withDeadline(grpc::ClientContext* context) {
  context->set_deadline(std::chrono::system_clock::now() + kCallTimeout);
}

// A unary request as raw bytes (ids substituted when the bytes parse as the request type).
template <typename Request>
void unary(const std::string& method, const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  Request typed;
  if (typed.ParseFromString(bytes)) {
    substituteIds(&typed);
    typed.SerializeToString(&bytes);
  }
  grpc::GenericStub stub(farmUnderTest().channel);
  grpc::ClientContext context;
  withDeadline(&context);
  grpc::Slice slice(bytes);
  grpc::ByteBuffer request(&slice, 1), response;
  std::promise<void> done;
  stub.UnaryCall(&context, method, grpc::StubOptions(), &request, &response,
                 [&](grpc::Status) { done.set_value(); });
  done.get_future().wait();
}

// A client stream of parsed messages.
template <typename Request, typename Response, typename Start>
void clientStream(Start start, const uint8_t* data, size_t size) {
  grpc::ClientContext context;
  withDeadline(&context);
  Response response;
  auto writer = start(&context, &response);
  std::string part;
  while (nextPart(data, size, &part)) {
    Request message;
    if (!message.ParseFromString(part)) continue;
    substituteHeader(&message, 0);
    if (!writer->Write(message)) break;
  }
  writer->WritesDone();
  writer->Finish();
}

// A server stream: read until it ends or the deadline passes.
template <typename Request, typename Item, typename Start>
void serverStream(Start start, const uint8_t* data, size_t size) {
  Request request;
  if (!request.ParseFromArray(data, int(size))) return;
  substituteIds(&request);
  grpc::ClientContext context;
  withDeadline(&context);
  auto reader = start(&context, request);
  Item item;
  while (reader->Read(&item)) {
  }
  reader->Finish();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (1 << 20)) return 0;
  Farm& f = farmUnderTest();
  auto client = v1::ClientApi::NewStub(f.channel);
  auto worker = v1::WorkerApi::NewStub(f.channel);
  const uint8_t method = data[0];
  ++data;
  --size;
  switch (method % 12) {
    case 0:
      unary<v1::MissingBlobsRequest>("/farm.v1.ClientApi/MissingBlobs", data, size);
      break;
    case 1:
      clientStream<v1::SubmitJobRequest, v1::SubmitJobResponse>(
          [&](grpc::ClientContext* c, v1::SubmitJobResponse* r) { return client->SubmitJob(c, r); },
          data, size);
      break;
    case 2:
      unary<v1::GetProgressRequest>("/farm.v1.ClientApi/GetProgress", data, size);
      break;
    case 3:
      serverStream<v1::FetchImageRequest, v1::ImageChunk>(
          [&](grpc::ClientContext* c, const v1::FetchImageRequest& r) {
            return client->FetchImage(c, r);
          },
          data, size);
      break;
    case 4:
      unary<v1::CancelJobRequest>("/farm.v1.ClientApi/CancelJob", data, size);
      break;
    case 5:
      unary<v1::ListJobsRequest>("/farm.v1.ClientApi/ListJobs", data, size);
      break;
    case 6:
      serverStream<v1::WatchJobRequest, v1::JobProgress>(
          [&](grpc::ClientContext* c, const v1::WatchJobRequest& r) {
            return client->WatchJob(c, r);
          },
          data, size);
      break;
    case 7:
      unary<v1::RegisterWorkerRequest>("/farm.v1.WorkerApi/RegisterWorker", data, size);
      break;
    case 8:
      unary<v1::LeaseChainsRequest>("/farm.v1.WorkerApi/LeaseChains", data, size);
      break;
    case 9:
      unary<v1::RenewLeasesRequest>("/farm.v1.WorkerApi/RenewLeases", data, size);
      break;
    case 10:
      serverStream<v1::FetchSceneBundleRequest, v1::SceneBundleChunk>(
          [&](grpc::ClientContext* c, const v1::FetchSceneBundleRequest& r) {
            return worker->FetchSceneBundle(c, r);
          },
          data, size);
      break;
    default:
      clientStream<v1::UploadFlushRequest, v1::UploadFlushResponse>(
          [&](grpc::ClientContext* c, v1::UploadFlushResponse* r) {
            return worker->UploadFlush(c, r);
          },
          data, size);
      break;
  }
  // The coordinator must still answer.
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  v1::ListJobsResponse jobs;
  if (!client->ListJobs(&context, v1::ListJobsRequest(), &jobs).ok()) {
    std::fprintf(stderr, "fuzz_requests: the coordinator stopped answering\n");
    std::abort();
  }
  return 0;
}
