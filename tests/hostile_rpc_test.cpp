// Broken and hostile requests against a real farm-coordinator process: each gets a gRPC status
// whose code and message say what was wrong, nothing already accepted is lost, and the
// coordinator keeps serving.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <future>
#include <limits>
#include <map>
#include <thread>

#include "common/film/pixel_allocation.h"
#include "proto/farm.grpc.pb.h"
#include "proto/sha256.h"
#include "proto/wire_limits.h"
#include "tests/test_support.h"
#include "worker/remote_chain_source.h"

namespace farm::testing {
namespace {

using std::chrono::seconds;

std::string fileContents(const std::string& path) {
  return readFile(path);
}

const std::string kSceneXml =
    fileContents(std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml");

class HostileRpcTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("rpc");
    coordinator_ = new CoordinatorProcess(scratch_->path(), /*leaseSeconds=*/30);
    ASSERT_TRUE(coordinator_->ok()) << coordinator_->log();
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(kMaxMessageBytes);
    args.SetMaxSendMessageSize(kMaxMessageBytes);
    channel_ = new std::shared_ptr<grpc::Channel>(grpc::CreateCustomChannel(
        coordinator_->address(), grpc::InsecureChannelCredentials(), args));
  }
  static void TearDownTestSuite() {
    delete channel_;
    if (coordinator_) {
      EXPECT_EQ(coordinator_->process().stop(), 0) << "the coordinator must survive the suite";
    }
    delete coordinator_;
    delete scratch_;
  }

  std::unique_ptr<v1::ClientApi::Stub> client() { return v1::ClientApi::NewStub(*channel_); }
  std::unique_ptr<v1::WorkerApi::Stub> worker() { return v1::WorkerApi::NewStub(*channel_); }

  static void withDeadline(grpc::ClientContext* context, int secondsFromNow = 15) {
    context->set_deadline(std::chrono::system_clock::now() + seconds(secondsFromNow));
  }

  static v1::RenderSettings smallSettings() {
    v1::RenderSettings s;
    s.set_algorithm(v1::PT);
    s.set_width(16);
    s.set_height(16);
    s.set_samples_per_pixel(4);
    s.set_mutations_per_pixel(4);
    s.set_seed(3);
    s.set_num_chains(2);
    s.set_large_step_probability(0.3f);
    return s;
  }

  struct File {
    std::string path, contents;
  };

  // SubmitJob with the given header fields; `upload` lists the files whose bytes are sent.
  grpc::Status submit(const v1::RenderSettings& settings, const std::vector<File>& listed,
                      const std::vector<File>& upload, const std::string& scenePath,
                      std::string* jobId = nullptr) {
    v1::SubmitJobRequest first;
    v1::JobHeader* header = first.mutable_header();
    *header->mutable_settings() = settings;
    header->set_scene_path(scenePath);
    for (const File& f : listed) {
      v1::BundleFile* entry = header->mutable_manifest()->add_files();
      entry->set_path(f.path);
      entry->set_size(f.contents.size());
      entry->set_hash(sha256Hex(f.contents));
    }
    std::vector<v1::SubmitJobRequest> messages{first};
    for (const File& f : upload) {
      v1::SubmitJobRequest chunk;
      chunk.mutable_chunk()->set_hash(sha256Hex(f.contents));
      chunk.mutable_chunk()->set_offset(0);
      chunk.mutable_chunk()->set_data(f.contents);
      messages.push_back(chunk);
    }
    return submitRaw(messages, jobId);
  }

  grpc::Status submitRaw(const std::vector<v1::SubmitJobRequest>& messages,
                         std::string* jobId = nullptr) {
    auto stub = client();
    grpc::ClientContext context;
    withDeadline(&context, 30);
    v1::SubmitJobResponse response;
    auto writer = stub->SubmitJob(&context, &response);
    for (const auto& m : messages) {
      if (!writer->Write(m)) break;
    }
    writer->WritesDone();
    grpc::Status status = writer->Finish();
    if (jobId) *jobId = response.job_id();
    return status;
  }

  v1::JobProgress progress(const std::string& jobId, grpc::Status* status) {
    auto stub = client();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::GetProgressRequest request;
    request.set_job_id(jobId);
    v1::JobProgress response;
    *status = stub->GetProgress(&context, request, &response);
    return response;
  }

  // Polls until the job leaves the loading and bootstrap phases.
  v1::JobProgress waitPastBootstrap(const std::string& jobId) {
    const auto deadline = std::chrono::steady_clock::now() + seconds(60);
    for (;;) {
      grpc::Status status;
      v1::JobProgress p = progress(jobId, &status);
      EXPECT_TRUE(status.ok()) << status.error_message();
      if (!status.ok() || p.phase() >= v1::RENDERING ||
          std::chrono::steady_clock::now() > deadline) {
        return p;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }

  v1::JobPhase cancel(const std::string& jobId) {
    auto stub = client();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::CancelJobRequest request;
    request.set_job_id(jobId);
    v1::CancelJobResponse response;
    grpc::Status status = stub->CancelJob(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.phase();
  }

  std::string registerWorker() {
    auto stub = worker();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::RegisterWorkerRequest request;
    request.set_protocol_version(kProtocolVersion);
    request.set_threads(1);
    request.add_capabilities("pt");
    v1::RegisterWorkerResponse response;
    grpc::Status status = stub->RegisterWorker(&context, request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.worker_id();
  }

  struct Flush {
    std::string workerId, jobId;
    uint32_t chain = 0, flushIndex = 0;
    uint64_t epoch = 0;
    int width = 16, height = 16;
    int64_t mutations = 10;
    std::vector<float> splats;
    std::string state = "10";
    bool corruptChecksum = false;
    // A worker that stops mid-upload: only this many splat bytes go out, then the stream ends
    // (or, with `vanish`, the call is cancelled as a dying process's would be).
    size_t sendBytes = SIZE_MAX;
    bool vanish = false;
    int64_t rejectedNan = 0, rejectedInfinite = 0, rejectedNegative = 0;
    std::vector<std::tuple<std::string, int64_t, int64_t>> tallies;
  };

  grpc::Status upload(const Flush& f, v1::UploadFlushResponse* response) {
    auto stub = worker();
    grpc::ClientContext context;
    withDeadline(&context, 30);
    auto writer = stub->UploadFlush(&context, response);
    const std::string bytes(reinterpret_cast<const char*>(f.splats.data()),
                            f.splats.size() * sizeof(float));
    v1::UploadFlushRequest first;
    v1::FlushHeader* h = first.mutable_header();
    h->set_worker_id(f.workerId);
    h->set_job_id(f.jobId);
    h->set_width(f.width);
    h->set_height(f.height);
    v1::FlushEntry* e = h->add_entries();  // a single flush: a batch of one
    e->set_chain_index(f.chain);
    e->set_flush_index(f.flushIndex);
    e->set_epoch(f.epoch);
    e->set_mutations(f.mutations);
    e->set_state(f.state);
    e->set_rejected_nan(f.rejectedNan);
    e->set_rejected_infinite(f.rejectedInfinite);
    e->set_rejected_negative(f.rejectedNegative);
    for (const auto& [name, proposed, accepted] : f.tallies) {
      v1::MutationTally* t = e->add_tallies();
      t->set_name(name);
      t->set_proposed(proposed);
      t->set_accepted(accepted);
    }
    h->set_splat_bytes(bytes.size());
    std::string checksum = sha256Hex(bytes + f.state);
    if (f.corruptChecksum) checksum[0] = checksum[0] == 'a' ? 'b' : 'a';
    h->set_checksum(checksum);
    writer->Write(first);
    v1::UploadFlushRequest chunk;
    chunk.set_splats(bytes.substr(0, std::min(bytes.size(), f.sendBytes)));
    writer->Write(chunk);
    if (f.vanish) {
      context.TryCancel();
    } else {
      writer->WritesDone();
    }
    return writer->Finish();
  }

  // A rendering job with one chain leased to a fresh worker.
  struct LeasedJob {
    std::string jobId, workerId;
    v1::ChainLease lease;
  };
  LeasedJob startJobAndLease() {
    LeasedJob out;
    grpc::Status s = submit(smallSettings(), {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}},
                            "scene.xml", &out.jobId);
    EXPECT_TRUE(s.ok()) << s.error_message();
    EXPECT_EQ(waitPastBootstrap(out.jobId).phase(), v1::RENDERING);
    out.workerId = registerWorker();
    auto stub = worker();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::LeaseChainsRequest request;
    request.set_worker_id(out.workerId);
    // Earlier tests' jobs may still have chains to lease: ask for many, keep one of ours.
    request.set_max_chains(64);
    v1::LeaseChainsResponse response;
    s = stub->LeaseChains(&context, request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    for (const v1::ChainLease& lease : response.leases()) {
      if (lease.spec().job_id() == out.jobId) out.lease = lease;
    }
    EXPECT_EQ(out.lease.spec().job_id(), out.jobId);
    return out;
  }

  static ScratchDir* scratch_;
  static CoordinatorProcess* coordinator_;
  static std::shared_ptr<grpc::Channel>* channel_;
};

ScratchDir* HostileRpcTest::scratch_ = nullptr;
CoordinatorProcess* HostileRpcTest::coordinator_ = nullptr;
std::shared_ptr<grpc::Channel>* HostileRpcTest::channel_ = nullptr;

#define EXPECT_STATUS(status, code, fragment)                                              \
  do {                                                                                     \
    const grpc::Status s_ = (status);                                                      \
    EXPECT_EQ(s_.error_code(), grpc::StatusCode::code) << s_.error_message();              \
    EXPECT_NE(s_.error_message().find(fragment), std::string::npos) << s_.error_message(); \
  } while (0)

TEST_F(HostileRpcTest, UnknownJobIdIsNotFound) {
  grpc::Status status;
  progress("job-doesnotexist", &status);
  EXPECT_STATUS(status, NOT_FOUND, "unknown job id 'job-doesnotexist'");
  progress("", &status);
  EXPECT_STATUS(status, INVALID_ARGUMENT, "job id is empty");

  auto stub = client();
  {
    grpc::ClientContext context;
    withDeadline(&context);
    v1::CancelJobRequest request;
    request.set_job_id("job-doesnotexist");
    v1::CancelJobResponse response;
    EXPECT_STATUS(stub->CancelJob(&context, request, &response), NOT_FOUND, "unknown job id");
  }
  {
    grpc::ClientContext context;
    withDeadline(&context);
    v1::FetchImageRequest request;
    request.set_job_id("job-doesnotexist");
    auto reader = stub->FetchImage(&context, request);
    v1::ImageChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    EXPECT_STATUS(reader->Finish(), NOT_FOUND, "unknown job id");
  }
}

TEST_F(HostileRpcTest, NanSettingsAreRejected) {
  v1::RenderSettings settings = smallSettings();
  settings.set_time_budget_seconds(std::numeric_limits<double>::quiet_NaN());
  EXPECT_STATUS(
      submit(settings, {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}}, "scene.xml"),
      INVALID_ARGUMENT, "time budget");
  settings = smallSettings();
  settings.set_large_step_probability(std::numeric_limits<float>::quiet_NaN());
  EXPECT_STATUS(submit(settings, {{"scene.xml", kSceneXml}}, {}, "scene.xml"), INVALID_ARGUMENT,
                "large-step probability");
  settings = smallSettings();
  settings.set_algorithm(v1::ALGORITHM_UNSPECIFIED);
  EXPECT_STATUS(submit(settings, {{"scene.xml", kSceneXml}}, {}, "scene.xml"), INVALID_ARGUMENT,
                "algorithm");
  settings = smallSettings();
  settings.set_samples_per_pixel(-5);
  EXPECT_STATUS(submit(settings, {{"scene.xml", kSceneXml}}, {}, "scene.xml"), INVALID_ARGUMENT,
                "samples per pixel");
}

TEST_F(HostileRpcTest, AbsurdResolutionIsRejected) {
  v1::RenderSettings settings = smallSettings();
  settings.set_width(1000000);
  settings.set_height(1000000);
  EXPECT_STATUS(
      submit(settings, {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}}, "scene.xml"),
      INVALID_ARGUMENT, "film size");
}

// The algorithms' own parameters get the same scrutiny as the film: a mutation mix without the
// bidirectional mutation (the chain would not be ergodic), weights that are not numbers, ERPT
// chains and lengths out of range, flush intervals and bootstrap sizes out of range, an
// algorithm or a shading-normal convention this coordinator does not know.
TEST_F(HostileRpcTest, BadAlgorithmParametersAreRejected) {
  v1::RenderSettings settings = smallSettings();
  settings.set_algorithm(v1::MLT);
  settings.mutable_mutation_mix()->set_lens_perturbation(1);
  const std::vector<File> files = {{"scene.xml", kSceneXml}};
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "bidirectional");
  settings.mutable_mutation_mix()->set_bidirectional(std::nan(""));
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "bidir");
  settings = smallSettings();
  settings.set_algorithm(v1::ERPT);
  settings.set_erpt_chains(-2);
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "ERPT chains");
  settings.set_erpt_chains(1);
  settings.set_erpt_length(1 << 30);
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "ERPT chain length");
  settings = smallSettings();
  settings.set_flush_interval(-5);
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "--flush-every");
  settings = smallSettings();
  settings.set_bootstrap_samples(int64_t(1) << 40);
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT,
                "--bootstrap-candidates");
  settings = smallSettings();
  settings.set_algorithm(v1::Algorithm(99));
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT, "algorithm");
  settings = smallSettings();
  settings.set_shading_normals(v1::ShadingNormals(7));
  EXPECT_STATUS(submit(settings, files, files, "scene.xml"), INVALID_ARGUMENT,
                "shading-normal convention");
  // And the coordinator keeps serving.
  EXPECT_TRUE(submit(smallSettings(), files, files, "scene.xml").ok());
}

TEST_F(HostileRpcTest, BundleWithoutTheSceneFileIsRejected) {
  EXPECT_STATUS(
      submit(smallSettings(), {{"other.xml", kSceneXml}}, {{"other.xml", kSceneXml}}, "scene.xml"),
      INVALID_ARGUMENT, "the scene file 'scene.xml' is not in the bundle");
  // Listed but never uploaded, and not on the coordinator from before.
  EXPECT_STATUS(
      submit(smallSettings(), {{"scene.xml", kSceneXml}, {"meshes/never-sent.obj", "v 0 0 0\n"}},
             {{"scene.xml", kSceneXml}}, "scene.xml"),
      INVALID_ARGUMENT, "missing 'meshes/never-sent.obj'");
  EXPECT_STATUS(submit(smallSettings(), {}, {}, "scene.xml"), INVALID_ARGUMENT, "no files");
}

TEST_F(HostileRpcTest, MalformedUploadsAreRejected) {
  // A path that climbs out of the bundle.
  EXPECT_STATUS(submit(smallSettings(), {{"../escape.xml", kSceneXml}}, {}, "../escape.xml"),
                INVALID_ARGUMENT, "'..'");
  // Bytes that do not hash to what the manifest says.
  v1::SubmitJobRequest header;
  *header.mutable_header()->mutable_settings() = smallSettings();
  header.mutable_header()->set_scene_path("scene.xml");
  v1::BundleFile* entry = header.mutable_header()->mutable_manifest()->add_files();
  const std::string claimed = kSceneXml + "<!-- a comment that will not arrive -->";
  entry->set_path("scene.xml");
  entry->set_size(claimed.size());
  entry->set_hash(sha256Hex(claimed));
  std::string tampered = claimed;
  tampered[10] ^= 1;
  v1::SubmitJobRequest chunk;
  chunk.mutable_chunk()->set_hash(entry->hash());
  chunk.mutable_chunk()->set_data(tampered);
  EXPECT_STATUS(submitRaw({header, chunk}), INVALID_ARGUMENT, "checksum mismatch");
  // A chunk at the wrong offset.
  chunk.mutable_chunk()->set_offset(5);
  chunk.mutable_chunk()->set_data(claimed);
  EXPECT_STATUS(submitRaw({header, chunk}), INVALID_ARGUMENT, "expected offset 0");
  // A chunk over the chunk limit.
  chunk.mutable_chunk()->set_offset(0);
  chunk.mutable_chunk()->set_data(std::string(kMaxChunkBytes + 1, 'x'));
  EXPECT_STATUS(submitRaw({header, chunk}), INVALID_ARGUMENT, "chunk limit");
  // No header first.
  EXPECT_STATUS(submitRaw({chunk}), INVALID_ARGUMENT, "first message must be the job header");
  // A hash that is not a hash.
  auto stub = client();
  grpc::ClientContext context;
  withDeadline(&context);
  v1::MissingBlobsRequest request;
  request.add_hashes("not-a-hash");
  v1::MissingBlobsResponse response;
  EXPECT_STATUS(stub->MissingBlobs(&context, request, &response), INVALID_ARGUMENT,
                "not a SHA-256 hash");
}

TEST_F(HostileRpcTest, IncompatibleWorkerIsRefused) {
  auto stub = worker();
  grpc::ClientContext context;
  withDeadline(&context);
  v1::RegisterWorkerRequest request;
  request.set_protocol_version(kProtocolVersion + 41);
  request.set_threads(4);
  request.add_capabilities("pssmlt");
  v1::RegisterWorkerResponse response;
  EXPECT_STATUS(stub->RegisterWorker(&context, request, &response), FAILED_PRECONDITION,
                "protocol");
}

TEST_F(HostileRpcTest, LeaseWaitOutsideItsRangeIsRejected) {
  const std::string workerId = registerWorker();
  auto stub = worker();
  for (int waitMs : {-1, 10001, std::numeric_limits<int32_t>::min()}) {
    grpc::ClientContext context;
    withDeadline(&context);
    v1::LeaseChainsRequest request;
    request.set_worker_id(workerId);
    request.set_max_chains(1);
    request.set_wait_ms(waitMs);
    v1::LeaseChainsResponse response;
    EXPECT_STATUS(stub->LeaseChains(&context, request, &response), INVALID_ARGUMENT,
                  "wait_ms must be in [0, 10000]");
  }
}

// A job's pixel allocation goes to a worker once, with the first of its leases; every work unit
// names it by hash, and a worker that says it holds it (a job before had the same one) gets none
// of its bytes. A request naming more than it may hold is refused.
TEST_F(HostileRpcTest, APixelAllocationTravelsOncePerWorker) {
  std::vector<float> density(16);
  for (size_t i = 0; i < density.size(); ++i) density[i] = 1.0f + float(i);
  const PixelAllocation allocation(16, 16, 4, density, std::vector<uint8_t>(density.size(), 0));
  const std::string bytes = allocation.encode();
  const std::string hash = sha256Hex(bytes);
  v1::RenderSettings settings = smallSettings();  // pt, which registerWorker() offers
  settings.set_num_chains(4);
  settings.set_pixel_allocation(bytes);
  const std::string workerId = registerWorker();
  auto stub = worker();
  // Leases the job's chains, with `held` named; how many of them carried the allocation's bytes.
  const auto leaseJob = [&](const std::string& jobId, const std::vector<std::string>& held) {
    grpc::ClientContext context;
    withDeadline(&context);
    v1::LeaseChainsRequest request;
    request.set_worker_id(workerId);
    request.set_max_chains(64);  // earlier tests' chains may come too
    for (const std::string& h : held) request.add_pixel_allocations_held(h);
    v1::LeaseChainsResponse response;
    const grpc::Status s = stub->LeaseChains(&context, request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    int leases = 0, withBytes = 0;
    for (const v1::ChainLease& lease : response.leases()) {
      if (lease.spec().job_id() != jobId) continue;
      ++leases;
      EXPECT_EQ(lease.spec().pixel_allocation_hash(), hash);
      EXPECT_TRUE(lease.spec().pixel_allocation().empty());
      EXPECT_TRUE(lease.settings().pixel_allocation().empty());
      if (!lease.pixel_allocation().empty()) {
        EXPECT_EQ(lease.pixel_allocation(), bytes);
        ++withBytes;
      }
    }
    EXPECT_EQ(leases, 4) << "the job's chains";
    return withBytes;
  };

  std::string first, second;
  ASSERT_TRUE(
      submit(settings, {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}}, "scene.xml", &first)
          .ok());
  ASSERT_EQ(waitPastBootstrap(first).phase(), v1::RENDERING);
  EXPECT_EQ(leaseJob(first, {}), 1);
  ASSERT_TRUE(
      submit(settings, {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}}, "scene.xml", &second)
          .ok());
  ASSERT_EQ(waitPastBootstrap(second).phase(), v1::RENDERING);
  EXPECT_EQ(leaseJob(second, {std::string(64, '0'), hash}), 0);

  grpc::ClientContext context;
  withDeadline(&context);
  v1::LeaseChainsRequest request;
  request.set_worker_id(workerId);
  request.set_max_chains(1);
  for (int i = 0; i <= kMaxHeldAllocations; ++i) request.add_pixel_allocations_held(hash);
  v1::LeaseChainsResponse response;
  EXPECT_STATUS(stub->LeaseChains(&context, request, &response), INVALID_ARGUMENT,
                "pixel allocations held");
}

// The worker's side of it: a real RemoteChainSource resolves every lease, takes a job's
// allocation once, names it when it leases the next job with the same one, and holds at most
// kMaxHeldAllocations (the oldest forgotten comes again when a job needs it).
TEST_F(HostileRpcTest, AWorkerTakesEachAllocationOnceAndHoldsTheLastSixteen) {
  const auto allocationBytes = [](int k) {
    std::vector<float> density(16, 1.0f);
    density[size_t(k % 16)] = 2.0f + float(k);
    return PixelAllocation(16, 16, 4, density, std::vector<uint8_t>(16, 0)).encode();
  };
  const auto submitWith = [&](const std::string& bytes) {
    v1::RenderSettings settings = smallSettings();
    settings.set_num_chains(1);
    settings.set_pixel_allocation(bytes);
    std::string id;
    EXPECT_TRUE(
        submit(settings, {{"scene.xml", kSceneXml}}, {{"scene.xml", kSceneXml}}, "scene.xml", &id)
            .ok());
    EXPECT_EQ(waitPastBootstrap(id).phase(), v1::RENDERING);
    return id;
  };
  RemoteSourceOptions options;
  options.coordinator = coordinator_->address();
  options.cacheDir = scratch_->path() + "/allocation-worker-cache";
  RemoteChainSource source(options);
  // Leases every chain there is; the ones of `jobs`, each checked to carry `bytes[job]`.
  const auto leaseJobs = [&](const std::map<std::string, std::string>& bytes) {
    size_t found = 0;
    for (const LeasedChain& chain : source.lease(64, 0)) {
      const auto it = bytes.find(chain.jobId);
      if (it == bytes.end()) continue;  // an earlier test's
      ++found;
      ASSERT_TRUE(chain.spec.pixelAllocation) << chain.jobId;
      EXPECT_EQ(chain.spec.pixelAllocation->encode(), it->second) << chain.jobId;
    }
    EXPECT_EQ(found, bytes.size()) << "every job's chain, resolved";
  };

  const std::string first = allocationBytes(0);
  leaseJobs({{submitWith(first), first}});
  EXPECT_EQ(source.allocationsReceived(), 1);
  leaseJobs({{submitWith(first), first}});
  EXPECT_EQ(source.allocationsReceived(), 1) << "the worker holds it and said so";

  std::map<std::string, std::string> many;
  for (int k = 1; k <= kMaxHeldAllocations; ++k)
    many[submitWith(allocationBytes(k))] = allocationBytes(k);
  leaseJobs(many);
  EXPECT_EQ(source.allocationsReceived(), 1 + kMaxHeldAllocations);
  // The first is now the least recently used beyond the limit: forgotten, and sent again.
  leaseJobs({{submitWith(first), first}});
  EXPECT_EQ(source.allocationsReceived(), 2 + kMaxHeldAllocations);
  leaseJobs(
      {{submitWith(allocationBytes(kMaxHeldAllocations)), allocationBytes(kMaxHeldAllocations)}});
  EXPECT_EQ(source.allocationsReceived(), 2 + kMaxHeldAllocations) << "the newest is held";
}

TEST_F(HostileRpcTest, BadFlushesAreRejectedAndDuplicatesCountOnce) {
  LeasedJob job = startJobAndLease();
  ASSERT_FALSE(job.jobId.empty());
  const uint32_t chain = job.lease.spec().chain_index();
  Flush flush;
  flush.workerId = job.workerId;
  flush.jobId = job.jobId;
  flush.chain = chain;
  flush.epoch = job.lease.epoch();
  flush.splats.assign(16 * 16 * 3, 0.25f);
  flush.rejectedInfinite = 2;
  flush.tallies = {{"small step", 4, 3}};
  v1::UploadFlushResponse response;

  // What is wrong with a chain's entry refuses the entry; what is wrong with the upload as a
  // whole (its film, its bytes, its worker) fails the call.
  const auto expectRefused = [&](const Flush& f, const std::string& reason) {
    grpc::Status status = upload(f, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.result(), v1::UploadFlushResponse::RESEND);
    ASSERT_EQ(response.entries_size(), 1);
    EXPECT_EQ(response.entries(0).result(), v1::UploadFlushResponse::REFUSED);
    EXPECT_NE(response.entries(0).reason().find(reason), std::string::npos)
        << response.entries(0).reason();
  };
  Flush unknownChain = flush;
  unknownChain.chain = 9999;
  expectRefused(unknownChain, "has no chain 9999");

  Flush corrupt = flush;
  corrupt.corruptChecksum = true;
  EXPECT_STATUS(upload(corrupt, &response), DATA_LOSS, "checksum mismatch");

  Flush wrongSize = flush;
  wrongSize.width = 8;
  wrongSize.splats.resize(8 * 16 * 3);
  EXPECT_STATUS(upload(wrongSize, &response), INVALID_ARGUMENT, "renders 16x16");

  Flush notANumber = flush;
  notANumber.splats[7] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_STATUS(upload(notANumber, &response), INVALID_ARGUMENT, "NaN");

  Flush unknownWorker = flush;
  unknownWorker.workerId = "worker-nobody";
  EXPECT_STATUS(upload(unknownWorker, &response), NOT_FOUND, "unknown worker id");

  Flush later = flush;
  later.flushIndex = 5;
  expectRefused(later, "arrived before flush 0");

  Flush negativeCount = flush;
  negativeCount.rejectedNan = -1;
  expectRefused(negativeCount, "negative count");
  Flush badTally = flush;
  badTally.tallies = {{"lens", 3, 7}};
  expectRefused(badTally, "malformed tally");

  // A worker that stops answering mid-upload leaves nothing behind: the stream that ends early
  // is refused, the one cancelled midway never reaches the job.
  Flush halfSent = flush;
  halfSent.sendBytes = flush.splats.size() * sizeof(float) / 2;
  EXPECT_STATUS(upload(halfSent, &response), INVALID_ARGUMENT, "flush ended after 1536 of 3072");
  halfSent.vanish = true;
  EXPECT_FALSE(upload(halfSent, &response).ok());
  {
    grpc::Status status;
    v1::JobProgress p = progress(job.jobId, &status);
    ASSERT_TRUE(status.ok());
    EXPECT_EQ(p.work_done(), 0) << "a broken upload counted";
  }

  // The same flush twice: accepted once, a duplicate the second time.
  ASSERT_TRUE(upload(flush, &response).ok());
  EXPECT_EQ(response.result(), v1::UploadFlushResponse::ACCEPTED);
  ASSERT_EQ(response.entries_size(), 1);
  EXPECT_FALSE(response.entries(0).stop());
  grpc::Status status = upload(flush, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.result(), v1::UploadFlushResponse::DUPLICATE);
  v1::JobProgress p = progress(job.jobId, &status);
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(p.work_done(), flush.mutations) << "the duplicate must not count";
  EXPECT_EQ(p.rejected_infinite(), 2) << "counts by cause, once";
  EXPECT_EQ(p.rejected_splats(), 2);
  ASSERT_EQ(p.tallies_size(), 1);
  EXPECT_EQ(p.tallies(0).proposed(), 4);

  // Cancelling ends the job; later flushes are discarded and told to stop.
  EXPECT_EQ(cancel(job.jobId), v1::CANCELLED);
  Flush next = flush;
  next.flushIndex = 1;
  ASSERT_TRUE(upload(next, &response).ok());
  EXPECT_EQ(response.result(), v1::UploadFlushResponse::DISCARDED);
  ASSERT_EQ(response.entries_size(), 1);
  EXPECT_TRUE(response.entries(0).stop());
  {
    auto stub = client();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::FetchImageRequest request;
    request.set_job_id(job.jobId);
    auto reader = stub->FetchImage(&context, request);
    v1::ImageChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    EXPECT_STATUS(reader->Finish(), FAILED_PRECONDITION, "was cancelled");
  }
}

TEST_F(HostileRpcTest, FetchWithoutWaitingOnARunningJobSaysSo) {
  LeasedJob job = startJobAndLease();  // one chain leased, never flushed: the job cannot end
  auto stub = client();
  grpc::ClientContext context;
  withDeadline(&context);
  v1::FetchImageRequest request;
  request.set_job_id(job.jobId);
  request.set_wait(false);
  auto reader = stub->FetchImage(&context, request);
  v1::ImageChunk chunk;
  EXPECT_FALSE(reader->Read(&chunk));
  EXPECT_STATUS(reader->Finish(), FAILED_PRECONDITION, "is still rendering");
  cancel(job.jobId);
}

TEST_F(HostileRpcTest, MalformedSceneFailsTheJobAndTheCoordinatorKeepsServing) {
  const std::string broken = "<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n  <shape type=";
  std::string badJob;
  grpc::Status s = submit(smallSettings(), {{"scene.xml", broken}}, {{"scene.xml", broken}},
                          "scene.xml", &badJob);
  ASSERT_TRUE(s.ok()) << s.error_message();
  v1::JobProgress p = waitPastBootstrap(badJob);
  EXPECT_EQ(p.phase(), v1::FAILED);
  EXPECT_NE(p.error().find("scene.xml"), std::string::npos) << p.error();
  EXPECT_EQ(p.error().find(scratch_->path()), std::string::npos)
      << "messages name bundle paths, not the coordinator's disk: " << p.error();

  // The failure is what fetch reports, too.
  {
    auto stub = client();
    grpc::ClientContext context;
    withDeadline(&context);
    v1::FetchImageRequest request;
    request.set_job_id(badJob);
    request.set_wait(true);
    auto reader = stub->FetchImage(&context, request);
    v1::ImageChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    EXPECT_STATUS(reader->Finish(), FAILED_PRECONDITION, "failed: ");
  }

  // Another job goes on to render.
  LeasedJob good = startJobAndLease();
  EXPECT_FALSE(good.lease.spec().job_id().empty());
  cancel(good.jobId);
}

TEST_F(HostileRpcTest, HealthServiceAnswersServing) {
  // grpc.health.v1.Health/Check through the generic stub: the request {service: ""} is empty on
  // the wire, and the answer {status: SERVING} is field 1 = 1, i.e. bytes 08 01.
  grpc::GenericStub stub(*channel_);
  grpc::ClientContext context;
  withDeadline(&context);
  grpc::ByteBuffer request, response;
  grpc::Slice empty("", 0);
  request = grpc::ByteBuffer(&empty, 1);
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&](grpc::Status s) { done.set_value(s); });
  grpc::Status status = done.get_future().get();
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const grpc::Slice& slice : slices) {
    bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  }
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));
}

}  // namespace
}  // namespace farm::testing
