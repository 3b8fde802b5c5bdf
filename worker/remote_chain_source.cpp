#include "worker/remote_chain_source.h"

#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "proto/bundle_manifest.h"
#include "proto/convert.h"
#include "proto/farm.grpc.pb.h"
#include "proto/sha256.h"
#include "proto/splat_codec.h"
#include "proto/wire_limits.h"
#include "worker/scene_cache.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "splat buffers travel as little-endian floats; add byte swapping for this host"
#endif

namespace farm {
namespace {

constexpr auto kUnaryDeadline = std::chrono::seconds(15);
constexpr auto kUploadDeadline = std::chrono::seconds(120);
constexpr auto kBundleDeadline = std::chrono::minutes(30);

void setDeadline(grpc::ClientContext* context, std::chrono::seconds timeout) {
  context->set_deadline(std::chrono::system_clock::now() + timeout);
}

bool isTransient(grpc::StatusCode code) {
  return code == grpc::StatusCode::UNAVAILABLE || code == grpc::StatusCode::DEADLINE_EXCEEDED ||
         code == grpc::StatusCode::RESOURCE_EXHAUSTED || code == grpc::StatusCode::DATA_LOSS ||
         code == grpc::StatusCode::ABORTED || code == grpc::StatusCode::CANCELLED;
}

std::string describe(const grpc::Status& s) {
  return s.error_message().empty() ? "gRPC status " + std::to_string(int(s.error_code()))
                                   : s.error_message();
}

std::string hostName() {
  char buffer[256] = {};
  if (gethostname(buffer, sizeof(buffer) - 1) != 0) return "unknown";
  return buffer;
}

}  // namespace

struct RemoteChainSource::Impl {
  RemoteSourceOptions options;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::WorkerApi::Stub> stub;
  std::unique_ptr<SceneCache> scenes;

  std::mutex mutex;  // guards the registration
  std::string workerId;
  double leaseSeconds = 30;
  std::mutex leaseMutex;  // guards the interruption
  bool interrupted = false;
  grpc::ClientContext* waitingLease = nullptr;  // the lease call in progress, if any

  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }

  // Registers if not registered yet; returns the worker id.
  std::string ensureRegistered(bool again = false) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!workerId.empty() && !again) return workerId;
    v1::RegisterWorkerRequest request;
    request.set_protocol_version(kProtocolVersion);
    request.set_worker_version(options.version);
    request.set_threads(options.threads);
    request.set_host(hostName());
    for (Algorithm a : allAlgorithms()) request.add_capabilities(algorithmName(a));
    v1::RegisterWorkerResponse response;
    grpc::ClientContext context;
    setDeadline(&context, kUnaryDeadline);
    grpc::Status status = stub->RegisterWorker(&context, request, &response);
    if (!status.ok()) {
      const std::string message = "cannot register with the coordinator at " + options.coordinator +
                                  ": " + describe(status);
      if (isTransient(status.error_code())) throw SourceUnavailable(message);
      throw SourceRefused(message);
    }
    workerId = response.worker_id();
    if (response.lease_seconds() > 0) leaseSeconds = response.lease_seconds();
    log("registered with " + options.coordinator + " as " + workerId + " (" +
        std::to_string(options.threads) + " threads)");
    return workerId;
  }

  // NOT_FOUND about our own id means the coordinator forgot us (it restarted): register again.
  static bool forgotWorker(const grpc::Status& s) {
    return s.error_code() == grpc::StatusCode::NOT_FOUND &&
           s.error_message().find("unknown worker id") != std::string::npos;
  }

  void fetchBundle(const std::string& hash, const std::string& dir) {
    log("fetching scene bundle " + hash.substr(0, 12) + "...");
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kBundleDeadline);
    v1::FetchSceneBundleRequest request;
    request.set_bundle_hash(hash);
    auto reader = stub->FetchSceneBundle(&context, request);
    v1::SceneBundleChunk message;
    if (!reader->Read(&message) || !message.has_manifest()) {
      grpc::Status status = reader->Finish();
      throw std::runtime_error("cannot fetch scene bundle " + hash + ": " +
                               (status.ok() ? "no manifest" : describe(status)));
    }
    BundleManifest manifest;
    for (const v1::BundleFile& f : message.manifest().files()) {
      manifest.push_back({f.path(), f.size(), f.hash()});
    }
    std::string problem = checkManifest(manifest);
    if (!problem.empty()) throw std::runtime_error("bundle " + hash + ": " + problem);
    if (bundleHash(manifest) != hash) {
      throw std::runtime_error("the coordinator sent a manifest that does not hash to " + hash);
    }
    // Files arrive in manifest order; empty ones carry no chunks.
    size_t index = 0;
    std::ofstream out;
    Sha256 digest;
    uint64_t written = 0;
    auto openNext = [&]() {
      while (index < manifest.size()) {
        const BundleEntry& e = manifest[index];
        const std::string path = dir + "/" + e.path;
        std::filesystem::create_directories(std::filesystem::path(path).parent_path());
        out = std::ofstream(path, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error("cannot write " + path);
        digest.reset();
        written = 0;
        if (e.size > 0) return;
        out.close();
        if (digest.hexDigest() != e.hash) {
          throw std::runtime_error("bundle file '" + e.path + "' arrived corrupted");
        }
        ++index;
      }
    };
    openNext();
    while (reader->Read(&message)) {
      if (!message.has_chunk() || index >= manifest.size()) {
        throw std::runtime_error("bundle " + hash + ": unexpected message in the stream");
      }
      const BundleEntry& e = manifest[index];
      const v1::BlobChunk& chunk = message.chunk();
      if (chunk.hash() != e.hash || chunk.offset() != written ||
          chunk.data().size() > e.size - written) {
        throw std::runtime_error("bundle " + hash + ": chunk out of order for '" + e.path + "'");
      }
      out.write(chunk.data().data(), std::streamsize(chunk.data().size()));
      digest.update(chunk.data());
      written += chunk.data().size();
      if (written == e.size) {
        out.close();
        if (!out) throw std::runtime_error("cannot write bundle file '" + e.path + "'");
        if (digest.hexDigest() != e.hash) {
          throw std::runtime_error("bundle file '" + e.path + "' arrived corrupted");
        }
        ++index;
        openNext();
      }
    }
    grpc::Status status = reader->Finish();
    if (!status.ok()) {
      throw std::runtime_error("cannot fetch scene bundle " + hash + ": " + describe(status));
    }
    if (index != manifest.size()) {
      throw std::runtime_error("scene bundle " + hash + " ended before '" + manifest[index].path +
                               "' was complete");
    }
    log("scene bundle " + hash.substr(0, 12) + " cached (" + std::to_string(manifest.size()) +
        " files)");
  }

  // One attempt at uploading a flush.
  grpc::Status uploadOnce(const std::string& id, const LeasedChain& chain, const ChainFlush& flush,
                          const EncodedSplats& splats, const std::string& checksum,
                          v1::UploadFlushResponse* response) {
    grpc::ClientContext context;
    setDeadline(&context, std::chrono::duration_cast<std::chrono::seconds>(kUploadDeadline));
    auto writer = stub->UploadFlush(&context, response);
    v1::UploadFlushRequest message;
    v1::FlushHeader* header = message.mutable_header();
    header->set_worker_id(id);
    header->set_job_id(chain.jobId);
    header->set_chain_index(flush.chainIndex);
    header->set_flush_index(flush.flushIndex);
    header->set_epoch(chain.epoch);
    header->set_mutations(flush.mutations);
    header->set_width(flush.width);
    header->set_height(flush.height);
    header->set_rejected_splats(flush.rejected.total());
    header->set_rejected_nan(flush.rejected.nan);
    header->set_rejected_infinite(flush.rejected.infinite);
    header->set_rejected_negative(flush.rejected.negative);
    header->set_rays(flush.rays);
    header->set_state(flush.state);
    header->set_finished(flush.finished);
    for (const MutationTally& t : flush.tallies) {
      v1::MutationTally* tally = header->add_tallies();
      tally->set_name(t.name);
      tally->set_proposed(t.proposed);
      tally->set_accepted(t.accepted);
    }
    header->set_splat_bytes(splats.bytes.size());
    header->set_sparse(splats.sparse);
    header->set_compressed(splats.compressed);
    header->set_raw_splat_bytes(splats.rawBytes);
    header->set_checksum(checksum);
    bool open = writer->Write(message);
    const char* bytes = splats.bytes.data();
    const size_t total = splats.bytes.size();
    for (size_t offset = 0; open && offset < total; offset += kMaxChunkBytes) {
      v1::UploadFlushRequest chunk;
      chunk.set_splats(bytes + offset, std::min(kMaxChunkBytes, total - offset));
      open = writer->Write(chunk);
    }
    writer->WritesDone();
    return writer->Finish();
  }
};

RemoteChainSource::RemoteChainSource(RemoteSourceOptions options) : impl_(new Impl) {
  impl_->options = std::move(options);
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  impl_->channel = grpc::CreateCustomChannel(impl_->options.coordinator,
                                             grpc::InsecureChannelCredentials(), args);
  impl_->stub = v1::WorkerApi::NewStub(impl_->channel);
  Impl* impl = impl_.get();
  impl_->scenes = std::make_unique<SceneCache>(
      impl_->options.cacheDir,
      [impl](const std::string& hash, const std::string& dir) { impl->fetchBundle(hash, dir); });
}

RemoteChainSource::~RemoteChainSource() = default;

double RemoteChainSource::renewIntervalSeconds() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return std::max(0.2, impl_->leaseSeconds / 3);
}

std::vector<LeasedChain> RemoteChainSource::lease(int max, double waitSeconds) {
  const int waitMs = int(std::clamp(waitSeconds, 0.0, 10.0) * 1000);
  for (int attempt = 0;; ++attempt) {
    const std::string id = impl_->ensureRegistered(attempt > 0);
    v1::LeaseChainsRequest request;
    request.set_worker_id(id);
    request.set_max_chains(max);
    v1::LeaseChainsResponse response;
    grpc::ClientContext context;
    {
      std::lock_guard<std::mutex> lock(impl_->leaseMutex);
      request.set_wait_ms(impl_->interrupted ? 0 : waitMs);
      impl_->waitingLease = &context;
    }
    context.set_deadline(std::chrono::system_clock::now() + kUnaryDeadline +
                         std::chrono::milliseconds(request.wait_ms()));
    grpc::Status status = impl_->stub->LeaseChains(&context, request, &response);
    {
      std::lock_guard<std::mutex> lock(impl_->leaseMutex);
      impl_->waitingLease = nullptr;
      if (impl_->interrupted && status.error_code() == grpc::StatusCode::CANCELLED) return {};
    }
    if (Impl::forgotWorker(status) && attempt == 0) continue;
    if (!status.ok()) {
      const std::string message =
          "cannot lease chains from " + impl_->options.coordinator + ": " + describe(status);
      if (isTransient(status.error_code())) throw SourceUnavailable(message);
      throw std::runtime_error(message);
    }
    std::vector<LeasedChain> chains;
    for (const v1::ChainLease& lease : response.leases()) {
      LeasedChain chain;
      std::string problem;
      if (!fromProto(lease.spec(), &chain.spec, &problem) ||
          !fromProto(lease.settings(), &chain.settings, &problem)) {
        impl_->log("ignoring a malformed lease: " + problem);
        continue;
      }
      chain.jobId = lease.spec().job_id();
      chain.epoch = lease.epoch();
      chain.bundleHash = lease.bundle_hash();
      chain.scenePath = lease.scene_path();
      chains.push_back(std::move(chain));
    }
    return chains;
  }
}

void RemoteChainSource::interrupt() {
  std::lock_guard<std::mutex> lock(impl_->leaseMutex);
  impl_->interrupted = true;
  if (impl_->waitingLease) impl_->waitingLease->TryCancel();
}

std::shared_ptr<const RenderJob> RemoteChainSource::renderJob(const LeasedChain& chain) {
  return impl_->scenes->renderJob(chain);
}

FlushReceipt RemoteChainSource::upload(const LeasedChain& chain, ChainFlush&& flush) {
  // Encoded once, sent as often as it takes.
  const EncodedSplats splats = encodeSplats(flush.splats);
  Sha256 digest;
  digest.update(splats.bytes);
  digest.update(flush.state);
  const std::string checksum = digest.hexDigest();

  const auto giveUp = std::chrono::steady_clock::now() +
                      std::chrono::duration<double>(impl_->options.uploadRetrySeconds);
  double backoff = 0.1;
  bool reregistered = false;
  for (;;) {
    const std::string id = impl_->ensureRegistered();
    v1::UploadFlushResponse response;
    grpc::Status status = impl_->uploadOnce(id, chain, flush, splats, checksum, &response);
    if (status.ok()) {
      FlushReceipt receipt;
      receipt.accepted = response.result() == v1::UploadFlushResponse::ACCEPTED;
      receipt.duplicate = response.result() == v1::UploadFlushResponse::DUPLICATE;
      receipt.stop = response.stop() || response.result() == v1::UploadFlushResponse::DISCARDED;
      receipt.reason = response.reason();
      receipt.yielded = response.yielded();
      return receipt;
    }
    if (Impl::forgotWorker(status) && !reregistered) {
      reregistered = true;
      impl_->ensureRegistered(true);
      continue;
    }
    const std::string what = "flush " + std::to_string(flush.flushIndex) + " of chain " +
                             std::to_string(flush.chainIndex) + " of " + chain.jobId;
    if (!isTransient(status.error_code()) || std::chrono::steady_clock::now() > giveUp) {
      throw std::runtime_error("cannot deliver " + what + ": " + describe(status));
    }
    impl_->log("retrying " + what + ": " + describe(status));
    std::this_thread::sleep_for(std::chrono::duration<double>(backoff));
    backoff = std::min(backoff * 2, 5.0);
  }
}

std::vector<bool> RemoteChainSource::renew(const std::vector<const LeasedChain*>& chains) {
  std::vector<bool> lost(chains.size(), false);
  if (chains.empty()) return lost;
  const std::string id = impl_->ensureRegistered();
  v1::RenewLeasesRequest request;
  request.set_worker_id(id);
  for (const LeasedChain* chain : chains) {
    v1::LeaseRef* ref = request.add_leases();
    ref->set_job_id(chain->jobId);
    ref->set_chain_index(chain->spec.chainIndex);
    ref->set_epoch(chain->epoch);
  }
  v1::RenewLeasesResponse response;
  grpc::ClientContext context;
  setDeadline(&context, kUnaryDeadline);
  grpc::Status status = impl_->stub->RenewLeases(&context, request, &response);
  if (Impl::forgotWorker(status)) {
    lost.assign(chains.size(), true);
    return lost;
  }
  if (!status.ok()) {
    throw SourceUnavailable("cannot renew leases at " + impl_->options.coordinator + ": " +
                            describe(status));
  }
  for (const v1::LeaseRef& ref : response.lost()) {
    for (size_t i = 0; i < chains.size(); ++i) {
      if (chains[i]->jobId == ref.job_id() && chains[i]->spec.chainIndex == ref.chain_index() &&
          chains[i]->epoch == ref.epoch()) {
        lost[i] = true;
      }
    }
  }
  return lost;
}

}  // namespace farm
