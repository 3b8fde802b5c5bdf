#include "coordinator/grpc_service.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "coordinator/coordinator.h"
#include "proto/convert.h"
#include "proto/farm.grpc.pb.h"
#include "proto/sha256.h"
#include "proto/splat_codec.h"
#include "proto/transport_security.h"
#include "proto/wire_limits.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "splat buffers travel as little-endian floats; add byte swapping for this host"
#endif

namespace farm {
namespace {

grpc::Status toGrpc(const Status& s) {
  using grpc::StatusCode;
  switch (s.code()) {
    case farm::StatusCode::kOk:
      return grpc::Status::OK;
    case farm::StatusCode::kInvalidArgument:
      return {StatusCode::INVALID_ARGUMENT, s.message()};
    case farm::StatusCode::kNotFound:
      return {StatusCode::NOT_FOUND, s.message()};
    case farm::StatusCode::kFailedPrecondition:
      return {StatusCode::FAILED_PRECONDITION, s.message()};
    case farm::StatusCode::kResourceExhausted:
      return {StatusCode::RESOURCE_EXHAUSTED, s.message()};
    case farm::StatusCode::kDataLoss:
      return {StatusCode::DATA_LOSS, s.message()};
    case farm::StatusCode::kUnavailable:
      return {StatusCode::UNAVAILABLE, s.message()};
    case farm::StatusCode::kDeadlineExceeded:
      return {StatusCode::DEADLINE_EXCEEDED, s.message()};
    case farm::StatusCode::kCancelled:
      return {StatusCode::CANCELLED, s.message()};
    case farm::StatusCode::kInternal:
      return {StatusCode::INTERNAL, s.message()};
    case farm::StatusCode::kUnauthenticated:
      return {StatusCode::UNAUTHENTICATED, s.message()};
    case farm::StatusCode::kPermissionDenied:
      return {StatusCode::PERMISSION_DENIED, s.message()};
  }
  return {StatusCode::UNKNOWN, s.message()};
}

grpc::Status invalid(const std::string& message) {
  return {grpc::StatusCode::INVALID_ARGUMENT, message};
}

BundleManifest fromProto(const v1::BundleManifest& m) {
  BundleManifest manifest;
  for (const v1::BundleFile& f : m.files()) manifest.push_back({f.path(), f.size(), f.hash()});
  return manifest;
}

// Ids are short; a request with a huge or empty one is malformed, not merely unknown.
grpc::Status checkId(const std::string& id, const char* what) {
  if (id.empty()) return invalid(std::string(what) + " is empty");
  if (id.size() > 256) return invalid(std::string(what) + " is longer than 256 characters");
  return grpc::Status::OK;
}

// Streams a file in chunks; `wrap` puts each chunk into the stream's message type.
template <typename Message, typename Wrap>
grpc::Status streamFile(const std::string& path, const std::string& label,
                        grpc::ServerWriter<Message>* writer, const Wrap& wrap) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return {grpc::StatusCode::INTERNAL, "cannot read " + label + " on the coordinator"};
  const uint64_t size = uint64_t(in.tellg());
  in.seekg(0);
  std::string buffer;
  uint64_t offset = 0;
  do {
    buffer.resize(size_t(std::min<uint64_t>(kMaxChunkBytes, size - offset)));
    in.read(buffer.data(), std::streamsize(buffer.size()));
    if (!in) return {grpc::StatusCode::INTERNAL, "error reading " + label + " on the coordinator"};
    Message message;
    wrap(size, offset, buffer, &message);
    if (!writer->Write(message)) return {grpc::StatusCode::CANCELLED, "the client went away"};
    offset += buffer.size();
  } while (offset < size);
  return grpc::Status::OK;
}

// ---------------------------------------------------------------------------------------------

// The role's token check, first thing in every ClientApi and WorkerApi call (health and
// reflection stay open: probes and tools need no token).
grpc::Status allow(const CallGuard& guard, grpc::ServerContext* context, Role role) {
  CallCheck check = guard.check(*context, role);
  if (check.ok()) return grpc::Status::OK;
  return {check.code == CallCheck::Code::kPermissionDenied ? grpc::StatusCode::PERMISSION_DENIED
                                                           : grpc::StatusCode::UNAUTHENTICATED,
          check.message};
}

class ClientService final : public v1::ClientApi::Service {
 public:
  ClientService(Coordinator* coordinator, const CallGuard* guard)
      : coordinator_(coordinator), guard_(guard) {}
  static constexpr int kMaxWatches = 256;

  grpc::Status MissingBlobs(grpc::ServerContext* context, const v1::MissingBlobsRequest* request,
                            v1::MissingBlobsResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    if (request->hashes_size() > 1000000) return invalid("more than 10^6 hashes in one request");
    for (const std::string& hash : request->hashes()) {
      if (!isSha256Hex(hash)) {
        return invalid("'" + hash.substr(0, 80) + "' is not a SHA-256 hash (64 lowercase hex)");
      }
      if (!coordinator_->blobs().has(hash)) response->add_missing_hashes(hash);
    }
    return grpc::Status::OK;
  }

  grpc::Status SubmitJob(grpc::ServerContext* context,
                         grpc::ServerReader<v1::SubmitJobRequest>* reader,
                         v1::SubmitJobResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    v1::SubmitJobRequest message;
    if (!reader->Read(&message) || !message.has_header()) {
      return invalid("SubmitJob: the first message must be the job header");
    }
    const v1::JobHeader header = message.header();

    RenderSettings settings;
    std::string problem;
    if (!farm::fromProto(header.settings(), &settings, &problem)) {
      return invalid("invalid render settings: " + problem);
    }
    problem = settings.validate();
    if (!problem.empty()) return invalid("invalid render settings: " + problem);

    const BundleManifest manifest = fromProto(header.manifest());
    if (manifest.empty()) return invalid("the scene bundle lists no files");
    problem = checkManifest(manifest);
    if (!problem.empty()) return invalid("invalid bundle manifest: " + problem);
    bool hasScene = false;
    for (const BundleEntry& e : manifest) hasScene |= e.path == header.scene_path();
    if (!hasScene) {
      return invalid("the scene file '" + header.scene_path().substr(0, 200) +
                     "' is not in the bundle");
    }
    const bool hasReference = !header.reference().hash().empty();
    if (hasReference) {
      BundleManifest ref{{"reference.exr", header.reference().size(), header.reference().hash()}};
      problem = checkManifest(ref);
      if (!problem.empty()) return invalid("invalid reference image entry: " + problem);
    }

    // The blobs still to come: every listed file the store does not hold yet.
    struct Expected {
      uint64_t size;
      std::string label;
      std::unique_ptr<BlobStore::Writer> writer;
    };
    std::map<std::string, Expected> expected;
    std::map<std::string, std::string> labels;  // every blob of the job, stored or not
    auto expect = [&](const std::string& hash, uint64_t size, const std::string& label) {
      labels.emplace(hash, label);
      if (!coordinator_->blobs().has(hash)) expected.emplace(hash, Expected{size, label, nullptr});
    };
    for (const BundleEntry& e : manifest) expect(e.hash, e.size, e.path);
    if (hasReference) {
      expect(header.reference().hash(), header.reference().size(), "the reference image");
    }
    auto writerFor = [&](Expected& blob, const std::string& hash, grpc::Status* error) {
      if (!blob.writer) {
        Status s = coordinator_->blobs().beginWrite(hash, blob.size, blob.label, &blob.writer);
        if (!s.isOk()) *error = toGrpc(s);
      }
      return blob.writer.get();
    };
    // Empty files carry no chunks.
    for (auto& [hash, blob] : expected) {
      if (blob.size != 0) continue;
      grpc::Status error;
      BlobStore::Writer* writer = writerFor(blob, hash, &error);
      if (!writer) return error;
      Status s = writer->commit();
      if (!s.isOk()) return toGrpc(s);
    }

    while (reader->Read(&message)) {
      if (!message.has_chunk()) return invalid("SubmitJob: only the first message may be a header");
      const v1::BlobChunk& chunk = message.chunk();
      if (chunk.data().size() > kMaxChunkBytes) {
        return invalid("a chunk of " + std::to_string(chunk.data().size()) +
                       " bytes exceeds the chunk limit of " + std::to_string(kMaxChunkBytes));
      }
      auto it = expected.find(chunk.hash());
      if (it == expected.end()) {
        if (labels.count(chunk.hash())) continue;  // already stored: harmless resend
        return invalid("a chunk names blob '" + chunk.hash().substr(0, 80) +
                       "', which the manifest does not list");
      }
      grpc::Status error;
      BlobStore::Writer* writer = writerFor(it->second, it->first, &error);
      if (!writer) return error;
      if (writer->complete()) {
        return invalid("chunks of '" + it->second.label + "' exceed its declared size");
      }
      Status s = writer->append(chunk.offset(), chunk.data());
      if (!s.isOk()) return toGrpc(s);
      if (writer->complete()) {
        s = writer->commit();
        if (!s.isOk()) return toGrpc(s);
      }
    }
    for (const auto& [hash, label] : labels) {
      if (coordinator_->blobs().has(hash)) continue;
      auto it = expected.find(hash);
      if (it != expected.end() && it->second.writer && it->second.writer->received() > 0) {
        return invalid("upload of '" + label + "' ended after " +
                       std::to_string(it->second.writer->received()) + " of " +
                       std::to_string(it->second.size) + " bytes");
      }
      return invalid("the bundle is missing '" + label + "' (sha256 " + hash +
                     "): it was neither uploaded nor already on the coordinator");
    }

    JobSpec spec;
    spec.settings = settings;
    spec.bundleHash = coordinator_->blobs().registerBundle(manifest);
    Status s = coordinator_->blobs().materialize(spec.bundleHash, &spec.bundleRoot);
    if (!s.isOk()) return toGrpc(s);
    spec.bundleScenePath = header.scene_path();
    spec.scenePath = spec.bundleRoot + "/" + header.scene_path();
    if (hasReference) spec.referencePath = coordinator_->blobs().pathOf(header.reference().hash());
    spec.name = header.name().empty() ? header.scene_path() : header.name().substr(0, 200);
    const std::string bundleHash = spec.bundleHash;
    std::string jobId;
    s = coordinator_->submit(std::move(spec), &jobId);
    if (!s.isOk()) return toGrpc(s);
    response->set_job_id(jobId);
    response->set_bundle_hash(bundleHash);
    return grpc::Status::OK;
  }

  grpc::Status GetProgress(grpc::ServerContext* context, const v1::GetProgressRequest* request,
                           v1::JobProgress* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    grpc::Status check = checkId(request->job_id(), "job id");
    if (!check.ok()) return check;
    JobProgress progress;
    Status s = coordinator_->progress(request->job_id(), request->error_series_from(), &progress);
    if (!s.isOk()) return toGrpc(s);
    toProto(progress, response);
    return grpc::Status::OK;
  }

  // Progress every interval until the job ends, each error sample sent once. The call holds a
  // server thread, so watches are capped; each ends within a step of the watcher leaving or
  // the server stopping.
  grpc::Status WatchJob(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                        grpc::ServerWriter<v1::JobProgress>* writer) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    grpc::Status check = checkId(request->job_id(), "job id");
    if (!check.ok()) return check;
    const auto interval = std::chrono::milliseconds(
        request->interval_ms() == 0 ? 1000 : std::clamp(request->interval_ms(), 100u, 10000u));
    struct Slot {
      std::atomic<int>& count;
      ~Slot() { --count; }
    } slot{watches_};
    if (++watches_ > kMaxWatches) {
      return {grpc::StatusCode::RESOURCE_EXHAUSTED,
              std::to_string(kMaxWatches) +
                  " watches are open on this coordinator, the most "
                  "it serves; poll with GetProgress instead"};
    }
    uint32_t from = 0;
    for (;;) {
      JobProgress progress;
      Status s = coordinator_->progress(request->job_id(), from, &progress);
      if (!s.isOk()) return toGrpc(s);
      v1::JobProgress message;
      toProto(progress, &message);
      if (!writer->Write(message)) return {grpc::StatusCode::CANCELLED, "the watcher went away"};
      from = progress.errorSeriesTotal;
      if (isTerminal(progress.phase)) return grpc::Status::OK;
      const auto next = std::chrono::steady_clock::now() + interval;
      while (std::chrono::steady_clock::now() < next) {
        if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "the watcher went away"};
        if (stopping_) return {grpc::StatusCode::UNAVAILABLE, "the coordinator is shutting down"};
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }

  // Ends every watch at its next step (before the server's Shutdown waits for calls).
  void stop() { stopping_ = true; }

  grpc::Status FetchImage(grpc::ServerContext* context, const v1::FetchImageRequest* request,
                          grpc::ServerWriter<v1::ImageChunk>* writer) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    grpc::Status check = checkId(request->job_id(), "job id");
    if (!check.ok()) return check;
    if (request->wait()) {
      // Wait in short steps so a client that gives up (or a deadline) frees this thread.
      for (;;) {
        JobPhase phase;
        Status s =
            coordinator_->waitForEnd(request->job_id(), std::chrono::milliseconds(250), &phase);
        if (!s.isOk()) return toGrpc(s);
        if (isTerminal(phase)) break;
        if (context->IsCancelled()) {
          return {grpc::StatusCode::CANCELLED, "the client stopped waiting"};
        }
      }
    }
    std::string path;
    Status s = coordinator_->imageFile(request->job_id(), &path);
    if (!s.isOk()) return toGrpc(s);
    return streamFile<v1::ImageChunk>(
        path, "the image", writer,
        [](uint64_t total, uint64_t offset, const std::string& bytes, v1::ImageChunk* m) {
          m->set_total_size(total);
          m->set_offset(offset);
          m->set_data(bytes);
        });
  }

  grpc::Status CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                         v1::CancelJobResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    grpc::Status check = checkId(request->job_id(), "job id");
    if (!check.ok()) return check;
    JobPhase phase;
    Status s = coordinator_->cancel(request->job_id(), &phase);
    if (!s.isOk()) return toGrpc(s);
    response->set_phase(toProto(phase));
    return grpc::Status::OK;
  }

  grpc::Status ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest*,
                        v1::ListJobsResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kSubmit); !denied.ok()) return denied;
    for (const JobProgress& p : coordinator_->list()) {
      v1::JobSummary* job = response->add_jobs();
      job->set_job_id(p.jobId);
      job->set_phase(toProto(p.phase));
      job->set_fraction(p.fraction);
      job->set_name(p.name);
      job->set_algorithm(farm::toProto(p.settings.algorithm));
      job->set_elapsed_seconds(p.elapsedSeconds);
      job->set_error(p.error);
    }
    return grpc::Status::OK;
  }

 private:
  Coordinator* coordinator_;
  const CallGuard* guard_;
  std::atomic<int> watches_{0};
  std::atomic<bool> stopping_{false};
};

// ---------------------------------------------------------------------------------------------

class WorkerService final : public v1::WorkerApi::Service {
 public:
  WorkerService(Coordinator* coordinator, const CallGuard* guard)
      : coordinator_(coordinator), guard_(guard) {}

  grpc::Status RegisterWorker(grpc::ServerContext* context,
                              const v1::RegisterWorkerRequest* request,
                              v1::RegisterWorkerResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kWork); !denied.ok()) return denied;
    if (request->protocol_version() != kProtocolVersion) {
      return {grpc::StatusCode::FAILED_PRECONDITION,
              "worker speaks farm protocol " + std::to_string(request->protocol_version()) +
                  ", this coordinator speaks " + std::to_string(kProtocolVersion) +
                  ": run matching versions of farm-worker and farm-coordinator"};
    }
    WorkerInfo info;
    info.version = request->worker_version().substr(0, 100);
    info.host = request->host().substr(0, 256);
    info.threads = request->threads();
    for (const std::string& name : request->capabilities()) {
      Algorithm algorithm;
      if (parseAlgorithm(name, &algorithm)) info.capabilities.insert(algorithm);
    }
    std::string id;
    Status s = coordinator_->registerWorker(info, &id);
    if (!s.isOk()) return toGrpc(s);
    response->set_worker_id(id);
    response->set_protocol_version(kProtocolVersion);
    response->set_lease_seconds(coordinator_->leaseSeconds());
    return grpc::Status::OK;
  }

  grpc::Status LeaseChains(grpc::ServerContext* context, const v1::LeaseChainsRequest* request,
                           v1::LeaseChainsResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kWork); !denied.ok()) return denied;
    grpc::Status check = checkId(request->worker_id(), "worker id");
    if (!check.ok()) return check;
    const auto maxWait =
        std::chrono::duration_cast<std::chrono::milliseconds>(Coordinator::kMaxLeaseWait);
    if (request->wait_ms() < 0 || request->wait_ms() > maxWait.count()) {
      return invalid("wait_ms must be in [0, " + std::to_string(maxWait.count()) + "], got " +
                     std::to_string(request->wait_ms()));
    }
    if (request->pixel_allocations_held_size() > kMaxHeldAllocations) {
      return invalid("more than " + std::to_string(kMaxHeldAllocations) +
                     " pixel allocations held");
    }
    // An allocation's bytes go to a worker once, with the first lease that names it (a job's
    // chains share one, up to 320 KiB).
    std::set<std::string> held;
    for (const std::string& hash : request->pixel_allocations_held()) {
      if (!isSha256Hex(hash)) {
        return invalid("pixel allocation held '" + hash.substr(0, 80) + "' is not a SHA-256 hash");
      }
      held.insert(hash);
    }
    std::vector<WorkerLease> leases;
    Status s = coordinator_->leaseChains(request->worker_id(), request->max_chains(), &leases,
                                         std::chrono::milliseconds(request->wait_ms()),
                                         [context] { return context->IsCancelled(); });
    if (!s.isOk()) return toGrpc(s);
    const auto steadyNow = SteadyClock::now();
    const auto systemNow = std::chrono::system_clock::now();
    for (const WorkerLease& w : leases) {
      v1::ChainLease* lease = response->add_leases();
      *lease->mutable_spec() = farm::toProto(w.lease.spec);
      lease->set_epoch(w.lease.epoch);
      const auto deadline =
          systemNow + std::chrono::duration_cast<std::chrono::system_clock::duration>(
                          w.lease.deadline - steadyNow);
      lease->set_deadline_unix_ms(
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline.time_since_epoch())
              .count());
      lease->set_bundle_hash(w.bundleHash);
      lease->set_scene_path(w.bundleScenePath);
      // The work unit names its pixel allocation; the settings' copy would only fill the message.
      *lease->mutable_settings() = farm::toProto(w.settings, WithAllocation::kLeftOut);
      const std::string& hash = lease->spec().pixel_allocation_hash();
      if (!hash.empty() && held.insert(hash).second) {
        lease->set_pixel_allocation(w.lease.spec.pixelAllocation->encode());
      }
    }
    if (leases.empty()) response->set_retry_after_ms(500);
    return grpc::Status::OK;
  }

  grpc::Status RenewLeases(grpc::ServerContext* context, const v1::RenewLeasesRequest* request,
                           v1::RenewLeasesResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kWork); !denied.ok()) return denied;
    grpc::Status check = checkId(request->worker_id(), "worker id");
    if (!check.ok()) return check;
    if (request->leases_size() > 4096) return invalid("more than 4096 leases in one renewal");
    std::vector<LeaseRef> refs, lost;
    for (const v1::LeaseRef& r : request->leases()) {
      refs.push_back({r.job_id(), r.chain_index(), r.epoch()});
    }
    Status s = coordinator_->renewLeases(request->worker_id(), refs, &lost);
    if (!s.isOk()) return toGrpc(s);
    for (const LeaseRef& r : lost) {
      v1::LeaseRef* m = response->add_lost();
      m->set_job_id(r.jobId);
      m->set_chain_index(r.chain);
      m->set_epoch(r.epoch);
    }
    return grpc::Status::OK;
  }

  grpc::Status FetchSceneBundle(grpc::ServerContext* context,
                                const v1::FetchSceneBundleRequest* request,
                                grpc::ServerWriter<v1::SceneBundleChunk>* writer) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kWork); !denied.ok()) return denied;
    if (!isSha256Hex(request->bundle_hash())) {
      return invalid("bundle hash '" + request->bundle_hash().substr(0, 80) +
                     "' is not a SHA-256 hash");
    }
    BundleManifest manifest;
    if (!coordinator_->blobs().findBundle(request->bundle_hash(), &manifest)) {
      return {grpc::StatusCode::NOT_FOUND, "unknown scene bundle " + request->bundle_hash()};
    }
    v1::SceneBundleChunk first;
    for (const BundleEntry& e : manifest) {
      v1::BundleFile* f = first.mutable_manifest()->add_files();
      f->set_path(e.path);
      f->set_size(e.size);
      f->set_hash(e.hash);
    }
    if (!writer->Write(first)) return {grpc::StatusCode::CANCELLED, "the worker went away"};
    for (const BundleEntry& e : manifest) {
      if (e.size == 0) continue;
      grpc::Status s = streamFile<v1::SceneBundleChunk>(
          coordinator_->blobs().pathOf(e.hash), "'" + e.path + "'", writer,
          [&](uint64_t, uint64_t offset, const std::string& bytes, v1::SceneBundleChunk* m) {
            m->mutable_chunk()->set_hash(e.hash);
            m->mutable_chunk()->set_offset(offset);
            m->mutable_chunk()->set_data(bytes);
          });
      if (!s.ok()) return s;
    }
    return grpc::Status::OK;
  }

  grpc::Status UploadFlush(grpc::ServerContext* context,
                           grpc::ServerReader<v1::UploadFlushRequest>* reader,
                           v1::UploadFlushResponse* response) override {
    if (grpc::Status denied = allow(*guard_, context, Role::kWork); !denied.ok()) return denied;
    v1::UploadFlushRequest message;
    if (!reader->Read(&message) || !message.has_header()) {
      return invalid("UploadFlush: the first message must be the flush header");
    }
    const v1::FlushHeader header = message.header();
    grpc::Status check = checkId(header.worker_id(), "worker id");
    if (!check.ok()) return check;
    check = checkId(header.job_id(), "job id");
    if (!check.ok()) return check;
    if (!isSha256Hex(header.checksum())) {
      return invalid("flush checksum is not a SHA-256 hash (64 lowercase hex)");
    }
    // Check the size against the job's film before receiving anything: the header alone must
    // not make the coordinator allocate what it likes.
    JobProgress job;
    Status s = coordinator_->progress(header.job_id(), UINT32_MAX, &job);
    if (!s.isOk()) return toGrpc(s);
    if (job.width <= 0 || header.width() != job.width || header.height() != job.height) {
      return invalid("flush is " + std::to_string(header.width()) + "x" +
                     std::to_string(header.height()) + " but job " + header.job_id() + " renders " +
                     std::to_string(job.width) + "x" + std::to_string(job.height));
    }
    const size_t values = size_t(job.width) * size_t(job.height) * 3;
    const uint64_t denseBytes = uint64_t(values) * sizeof(float);
    // Dense and uncompressed, the size is the film's; otherwise at most what a compressed
    // dense film can take (the decoder checks the rest).
    const uint64_t expectedBytes = header.splat_bytes();
    if ((!header.sparse() && !header.compressed() && expectedBytes != denseBytes) ||
        expectedBytes > maxEncodedSplatBytes(values)) {
      return invalid("flush announces " + std::to_string(header.splat_bytes()) +
                     " splat bytes; a " + std::to_string(job.width) + "x" +
                     std::to_string(job.height) + " film takes " + std::to_string(denseBytes));
    }
    std::string bytes;
    bytes.reserve(size_t(expectedBytes));
    while (reader->Read(&message)) {
      if (!message.has_splats())
        return invalid("UploadFlush: only the first message may be a header");
      const std::string& chunk = message.splats();
      if (chunk.size() > kMaxChunkBytes) {
        return invalid("a splat chunk of " + std::to_string(chunk.size()) +
                       " bytes exceeds the chunk limit of " + std::to_string(kMaxChunkBytes));
      }
      if (chunk.size() > expectedBytes - bytes.size()) {
        return invalid("splat chunks exceed the announced " + std::to_string(expectedBytes) +
                       " bytes");
      }
      bytes += chunk;
    }
    if (bytes.size() != expectedBytes) {
      return invalid("flush ended after " + std::to_string(bytes.size()) + " of " +
                     std::to_string(expectedBytes) + " splat bytes");
    }
    if (header.entries_size() == 0 || size_t(header.entries_size()) > kMaxBatchEntries) {
      return invalid("a flush holds " + std::to_string(header.entries_size()) +
                     " chains' entries; 1 to " + std::to_string(kMaxBatchEntries));
    }
    Sha256 digest;
    digest.update(bytes);
    for (const v1::FlushEntry& e : header.entries()) digest.update(e.state());
    const std::string actual = digest.hexDigest();
    if (actual != header.checksum()) {
      return {grpc::StatusCode::DATA_LOSS,
              "checksum mismatch: the header says " + header.checksum() +
                  ", the received splats and state hash to " + actual + " (resend the flush)"};
    }
    return accept(header, std::move(bytes), values, response);
  }

 private:
  static v1::UploadFlushResponse::Result toResult(FlushAck::Result r) {
    switch (r) {
      case FlushAck::Result::kAccepted:
        return v1::UploadFlushResponse::ACCEPTED;
      case FlushAck::Result::kDuplicate:
        return v1::UploadFlushResponse::DUPLICATE;
      case FlushAck::Result::kDiscarded:
        return v1::UploadFlushResponse::DISCARDED;
      case FlushAck::Result::kResend:
        return v1::UploadFlushResponse::RESEND;
      case FlushAck::Result::kRefused:
        return v1::UploadFlushResponse::REFUSED;
    }
    return v1::UploadFlushResponse::RESULT_UNSPECIFIED;
  }

  // The rest of UploadFlush, its bytes received and checked: a batch of one or more chains'
  // flushes (a single flush is a batch of one).
  grpc::Status accept(const v1::FlushHeader& header, std::string&& bytes, size_t values,
                      v1::UploadFlushResponse* response) {
    FlushBatch batch;
    for (const v1::FlushEntry& e : header.entries()) {
      batch.entries.push_back(::farm::fromProto(e));
      batch.epochs.push_back(e.epoch());
    }
    batch.film.width = header.width();
    batch.film.height = header.height();
    EncodedSplats encoded;
    encoded.sparse = header.sparse();
    encoded.compressed = header.compressed();
    encoded.rawBytes = header.raw_splat_bytes();
    encoded.bytes = std::move(bytes);
    std::string problem;
    if (!decodeSplats(encoded, values, &batch.film.splats, &problem)) {
      return invalid(std::string(header.entries_size() == 1 ? "a flush" : "a batch") + " of " +
                     std::to_string(header.entries_size()) + " chains: " + problem);
    }
    std::vector<FlushAck> acks;
    Status s = coordinator_->acceptBatch(header.worker_id(), header.job_id(), std::move(batch),
                                         &acks, &encoded);
    if (!s.isOk()) return toGrpc(s);
    bool all[3] = {true, true, true};  // accepted, duplicate, discarded
    for (size_t i = 0; i < acks.size(); ++i) {
      v1::UploadFlushResponse::EntryResult* r = response->add_entries();
      r->set_chain_index(header.entries(int(i)).chain_index());
      r->set_result(toResult(acks[i].result));
      r->set_stop(acks[i].stop);
      r->set_reason(acks[i].reason);
      r->set_yielded(acks[i].yielded);
      all[0] &= acks[i].result == FlushAck::Result::kAccepted;
      all[1] &= acks[i].result == FlushAck::Result::kDuplicate;
      all[2] &= acks[i].result == FlushAck::Result::kDiscarded;
    }
    response->set_result(all[0]   ? v1::UploadFlushResponse::ACCEPTED
                         : all[1] ? v1::UploadFlushResponse::DUPLICATE
                         : all[2] ? v1::UploadFlushResponse::DISCARDED
                                  : v1::UploadFlushResponse::RESEND);
    return grpc::Status::OK;
  }

  Coordinator* coordinator_;
  const CallGuard* guard_;
};

class GrpcCoordinatorServer final : public CoordinatorServer {
 public:
  GrpcCoordinatorServer(Coordinator* coordinator, std::unique_ptr<CallGuard> guard)
      : coordinator_(coordinator),
        guard_(std::move(guard)),
        clientService_(coordinator, guard_.get()),
        workerService_(coordinator, guard_.get()) {}

  bool start(const std::string& address, std::string* error) {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
    grpc::ServerBuilder builder;
    builder.AddListeningPort(address, guard_->credentials(), &port_);
    serverKeepalive(&builder);
    builder.SetMaxReceiveMessageSize(kMaxMessageBytes);
    builder.SetMaxSendMessageSize(kMaxMessageBytes);
    builder.RegisterService(&clientService_);
    builder.RegisterService(&workerService_);
    server_ = builder.BuildAndStart();
    if (!server_ || port_ == 0) {
      *error = "cannot listen on '" + address +
               "' (in use, not an address of this host, or not HOST:PORT)";
      server_.reset();
      return false;
    }
    return true;
  }

  int port() const override { return port_; }
  std::string security() const override { return guard_->describe(); }
  const CallGuard* guard() const override { return guard_.get(); }

  void shutdown() override {
    if (!server_) return;
    coordinator_->releaseLeaseWaiters();  // else Shutdown waits out their calls
    clientService_.stop();                // and watches
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    server_->Wait();
    server_.reset();
  }

  ~GrpcCoordinatorServer() override { shutdown(); }

 private:
  Coordinator* coordinator_;
  std::unique_ptr<CallGuard> guard_;  // before the services, which hold it
  ClientService clientService_;
  WorkerService workerService_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

class GrpcHealthServer final : public HealthServer {
 public:
  bool start(const std::string& address, std::string* error) {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::ServerBuilder builder;
    builder.AddListeningPort(address, grpc::InsecureServerCredentials(), &port_);
    server_ = builder.BuildAndStart();  // the default health service is its only one
    if (!server_ || port_ == 0) {
      *error = "cannot serve health checks on '" + address + "' (in use, or not HOST:PORT)";
      server_.reset();
      return false;
    }
    return true;
  }
  int port() const override { return port_; }
  void shutdown() override {
    if (!server_) return;
    server_->GetHealthCheckService()->Shutdown();
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
    server_.reset();
  }
  ~GrpcHealthServer() override { shutdown(); }

 private:
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
};

}  // namespace

std::unique_ptr<HealthServer> HealthServer::start(const std::string& address, std::string* error) {
  auto server = std::make_unique<GrpcHealthServer>();
  if (!server->start(address, error)) return nullptr;
  return server;
}

std::unique_ptr<CoordinatorServer> CoordinatorServer::start(const std::string& address,
                                                            Coordinator* coordinator,
                                                            const ServerSecurity& security,
                                                            std::string* error) {
  std::unique_ptr<CallGuard> guard = CallGuard::load(address, security, error);
  if (!guard) return nullptr;
  auto server = std::make_unique<GrpcCoordinatorServer>(coordinator, std::move(guard));
  if (!server->start(address, error)) return nullptr;
  return server;
}

std::unique_ptr<CoordinatorServer> CoordinatorServer::start(const std::string& address,
                                                            Coordinator* coordinator,
                                                            std::string* error) {
  return start(address, coordinator, ServerSecurity{}, error);
}

}  // namespace farm
