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
#include "proto/transport_security.h"
#include "proto/wire_limits.h"
#include "worker/flush_batcher.h"
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
  std::unique_ptr<FlushBatcher> batcher;  // with a batch window

  std::mutex mutex;  // guards the registration
  std::string workerId;
  double leaseSeconds = 30;
  std::mutex leaseMutex;  // guards the interruption
  bool interrupted = false;
  grpc::ClientContext* waitingLease = nullptr;  // the lease call in progress, if any
  // The pixel allocations this worker holds, most recently used last (at most
  // kMaxHeldAllocations between leases): a job's travels once, with its first lease here.
  std::mutex allocationMutex;
  std::vector<std::pair<std::string, std::shared_ptr<const PixelAllocation>>> allocations;
  int allocationsReceived = 0;

  // Takes the allocations that came with `response`'s leases, resolves every lease's work unit
  // against what is held, and then forgets the least recently used beyond the limit (not before:
  // a later lease of the same response may name one the request said was held).
  std::vector<LeasedChain> takeLeases(const v1::LeaseChainsResponse& response) {
    std::lock_guard<std::mutex> lock(allocationMutex);
    const auto use = [&](const std::string& hash) -> std::shared_ptr<const PixelAllocation> {
      for (size_t i = 0; i < allocations.size(); ++i) {
        if (allocations[i].first != hash) continue;
        std::rotate(allocations.begin() + long(i), allocations.begin() + long(i) + 1,
                    allocations.end());
        return allocations.back().second;
      }
      return nullptr;
    };
    std::vector<LeasedChain> chains;
    for (const v1::ChainLease& lease : response.leases()) {
      LeasedChain chain;
      std::string problem;
      const std::string& hash = lease.spec().pixel_allocation_hash();
      if (!lease.pixel_allocation().empty()) {
        ++allocationsReceived;
        if (!use(hash)) {
          std::shared_ptr<const PixelAllocation> allocation;
          if (!decodePixelAllocation(lease.pixel_allocation(), hash, &allocation, &problem)) {
            log("ignoring a malformed lease: " + problem);
            continue;
          }
          allocations.emplace_back(hash, std::move(allocation));
        }
      }
      if (!fromProto(lease.spec(), &chain.spec, &problem, use) ||
          !fromProto(lease.settings(), &chain.settings, &problem)) {
        log("ignoring a malformed lease: " + problem);
        continue;
      }
      chain.jobId = lease.spec().job_id();
      chain.epoch = lease.epoch();
      chain.bundleHash = lease.bundle_hash();
      chain.scenePath = lease.scene_path();
      chains.push_back(std::move(chain));
    }
    if (allocations.size() > size_t(kMaxHeldAllocations)) {
      allocations.erase(allocations.begin(),
                        allocations.end() - std::ptrdiff_t(kMaxHeldAllocations));
    }
    return chains;
  }

  void nameHeldAllocations(v1::LeaseChainsRequest* request) {
    std::lock_guard<std::mutex> lock(allocationMutex);
    for (const auto& held : allocations) request->add_pixel_allocations_held(held.first);
  }

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

  FlushReceipt uploadSingle(const LeasedChain& chain, ChainFlush&& flush);
  std::vector<BatchAnswer> sendBatch(const std::vector<BatchItem*>& items);
  // Uploads until it is answered, retrying what can be retried; throws when it cannot.
  void deliver(const LeasedChain& chain, const ChainFlush& flush,
               const std::vector<BatchItem*>& items, const EncodedSplats& splats,
               const std::string& checksum, const std::string& what,
               v1::UploadFlushResponse* response);

  // One attempt at uploading the flushes of `items` (one or more chains'), their film encoded in
  // `splats`; `flush` gives the film's size.
  grpc::Status uploadOnce(const std::string& id, const LeasedChain& chain, const ChainFlush& flush,
                          const std::vector<BatchItem*>& items, const EncodedSplats& splats,
                          const std::string& checksum, v1::UploadFlushResponse* response) {
    grpc::ClientContext context;
    setDeadline(&context, std::chrono::duration_cast<std::chrono::seconds>(kUploadDeadline));
    auto writer = stub->UploadFlush(&context, response);
    v1::UploadFlushRequest message;
    v1::FlushHeader* header = message.mutable_header();
    header->set_worker_id(id);
    header->set_job_id(chain.jobId);
    for (const BatchItem* item : items)
      toProto(item->flush, item->chain->epoch, header->add_entries());
    header->set_width(flush.width);
    header->set_height(flush.height);
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
  std::string error;
  impl_->channel =
      makeClientChannel(impl_->options.coordinator, impl_->options.security, args, &error);
  if (!impl_->channel) throw std::invalid_argument(error);
  impl_->stub = v1::WorkerApi::NewStub(impl_->channel);
  Impl* impl = impl_.get();
  if (impl_->options.batchWindowSeconds > 0) {
    impl_->batcher = std::make_unique<FlushBatcher>(
        impl_->options.batchWindowSeconds,
        [impl](const std::vector<BatchItem*>& items) { return impl->sendBatch(items); });
  }
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
    impl_->nameHeldAllocations(&request);
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
    std::vector<LeasedChain> chains = impl_->takeLeases(response);
    if (impl_->batcher) {
      for (const LeasedChain& chain : chains)
        impl_->batcher->chainStarted(FlushBatcher::key(chain));
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
  if (impl_->batcher) return impl_->batcher->upload(chain, std::move(flush));
  return impl_->uploadSingle(chain, std::move(flush));
}

int RemoteChainSource::allocationsReceived() const {
  std::lock_guard<std::mutex> lock(impl_->allocationMutex);
  return impl_->allocationsReceived;
}

FlushBatcher::Stats RemoteChainSource::batchStats() const {
  return impl_->batcher ? impl_->batcher->stats() : FlushBatcher::Stats();
}

void RemoteChainSource::release(const LeasedChain& chain) {
  if (impl_->batcher) impl_->batcher->chainEnded(FlushBatcher::key(chain));
}

namespace {

FlushReceipt receiptFrom(v1::UploadFlushResponse::Result result, bool stop,
                         const std::string& reason, bool yielded) {
  FlushReceipt receipt;
  receipt.accepted = result == v1::UploadFlushResponse::ACCEPTED;
  receipt.duplicate = result == v1::UploadFlushResponse::DUPLICATE;
  receipt.stop = stop || result == v1::UploadFlushResponse::DISCARDED;
  receipt.reason = reason;
  receipt.yielded = yielded;
  return receipt;
}

}  // namespace

FlushReceipt RemoteChainSource::Impl::uploadSingle(const LeasedChain& chain, ChainFlush&& flush) {
  BatchItem item;  // a single flush is a batch of one
  item.chain = &chain;
  item.flush = std::move(flush);
  const BatchAnswer answer = sendBatch({&item}).front();
  if (answer.kind == BatchAnswer::Kind::kReceipt) return answer.receipt;
  throw std::runtime_error(answer.kind == BatchAnswer::Kind::kError
                               ? answer.error
                               : "the coordinator held back a batch of one flush of " +
                                     chain.jobId + " for its own sake");
}

std::vector<BatchAnswer> RemoteChainSource::Impl::sendBatch(const std::vector<BatchItem*>& items) {
  // The films summed in double, sent in float as each chain's is (one alone goes as it is).
  const ChainFlush& first = items.front()->flush;
  ChainFlush film;  // its size; its splats when there is a sum to hold
  film.width = first.width;
  film.height = first.height;
  if (items.size() > 1) {
    const size_t values = first.splats.size();
    for (const BatchItem* item : items) {
      if (item->flush.splats.size() != values) {
        throw std::runtime_error("the flushes of one job differ in film size");
      }
    }
    // A block at a time, so that the double sum never holds more than a block of the film.
    constexpr size_t kBlock = 1 << 14;
    std::vector<double> sum(std::min(values, kBlock));
    film.splats.resize(values);
    for (size_t start = 0; start < values; start += kBlock) {
      const size_t end = std::min(values, start + kBlock);
      std::fill(sum.begin(), sum.end(), 0.0);
      for (const BatchItem* item : items) {
        const std::vector<float>& splats = item->flush.splats;
        for (size_t i = start; i < end; ++i) sum[i - start] += double(splats[i]);
      }
      for (size_t i = start; i < end; ++i) film.splats[i] = float(sum[i - start]);
    }
  }
  const EncodedSplats splats = encodeSplats(items.size() == 1 ? first.splats : film.splats);
  Sha256 digest;
  digest.update(splats.bytes);
  for (const BatchItem* item : items) digest.update(item->flush.state);
  const std::string checksum = digest.hexDigest();
  v1::UploadFlushResponse response;
  const std::string what = items.size() == 1 ? "flush " + std::to_string(first.flushIndex) +
                                                   " of chain " + std::to_string(first.chainIndex) +
                                                   " of " + items[0]->chain->jobId
                                             : "a batch of " + std::to_string(items.size()) +
                                                   " flushes of " + items.front()->chain->jobId;
  deliver(*items.front()->chain, film, items, splats, checksum, what, &response);
  if (response.entries_size() != int(items.size())) {
    throw std::runtime_error("the coordinator answered " + std::to_string(response.entries_size()) +
                             " of a batch of " + std::to_string(items.size()) + " flushes");
  }
  std::vector<BatchAnswer> answers(items.size());
  for (size_t i = 0; i < items.size(); ++i) {
    const v1::UploadFlushResponse::EntryResult& r = response.entries(int(i));
    BatchAnswer& a = answers[i];
    if (r.result() == v1::UploadFlushResponse::RESEND) {
      a.kind = BatchAnswer::Kind::kResend;
    } else if (r.result() == v1::UploadFlushResponse::REFUSED) {
      a.kind = BatchAnswer::Kind::kError;
      a.error = "flush " + std::to_string(items[i]->flush.flushIndex) + " of chain " +
                std::to_string(items[i]->flush.chainIndex) + " refused: " + r.reason();
    } else {
      a.kind = BatchAnswer::Kind::kReceipt;
      a.receipt = receiptFrom(r.result(), r.stop(), r.reason(), r.yielded());
    }
  }
  return answers;
}

void RemoteChainSource::Impl::deliver(const LeasedChain& chain, const ChainFlush& flush,
                                      const std::vector<BatchItem*>& items,
                                      const EncodedSplats& splats, const std::string& checksum,
                                      const std::string& what, v1::UploadFlushResponse* response) {
  const auto giveUp =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(options.uploadRetrySeconds);
  double backoff = 0.1;
  bool reregistered = false;
  for (;;) {
    const std::string id = ensureRegistered();
    response->Clear();
    grpc::Status status = uploadOnce(id, chain, flush, items, splats, checksum, response);
    if (status.ok()) return;
    if (forgotWorker(status) && !reregistered) {
      reregistered = true;
      ensureRegistered(true);
      continue;
    }
    if (!isTransient(status.error_code()) || std::chrono::steady_clock::now() > giveUp) {
      throw std::runtime_error("cannot deliver " + what + ": " + describe(status));
    }
    log("retrying " + what + ": " + describe(status));
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
