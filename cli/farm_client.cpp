#include "cli/farm_client.h"

#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "proto/convert.h"
#include "proto/farm.grpc.pb.h"
#include "proto/sha256.h"
#include "proto/transport_security.h"
#include "proto/wire_limits.h"

namespace farm {
namespace {

constexpr auto kUnaryDeadline = std::chrono::seconds(15);
constexpr auto kTransferDeadline = std::chrono::minutes(30);

}  // namespace

struct FarmClient::Impl {
  std::string address;
  std::string setupError;  // a TLS or token file that could not be used; no channel then
  bool tls = false;
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<v1::ClientApi::Stub> stub;

  Status fail(const grpc::Status& s) const {
    switch (s.error_code()) {
      case grpc::StatusCode::UNAVAILABLE:
        return {StatusCode::kUnavailable,
                "cannot reach the coordinator at " + address + " (" + s.error_message() + ")"};
      case grpc::StatusCode::DEADLINE_EXCEEDED:
        return {StatusCode::kDeadlineExceeded,
                "the coordinator at " + address + " did not answer in time"};
      case grpc::StatusCode::INVALID_ARGUMENT:
        return {StatusCode::kInvalidArgument, s.error_message()};
      case grpc::StatusCode::NOT_FOUND:
        return {StatusCode::kNotFound, s.error_message()};
      case grpc::StatusCode::FAILED_PRECONDITION:
        return {StatusCode::kFailedPrecondition, s.error_message()};
      case grpc::StatusCode::DATA_LOSS:
        return {StatusCode::kDataLoss, s.error_message()};
      case grpc::StatusCode::RESOURCE_EXHAUSTED:
        return {StatusCode::kResourceExhausted, s.error_message()};
      case grpc::StatusCode::UNAUTHENTICATED:
        return {StatusCode::kUnauthenticated,
                "the coordinator at " + address + " refused the call: " + s.error_message()};
      case grpc::StatusCode::PERMISSION_DENIED:
        return {StatusCode::kPermissionDenied,
                "the coordinator at " + address + " refused the call: " + s.error_message()};
      default:
        return {StatusCode::kInternal, "coordinator at " + address + ": " + s.error_message()};
    }
  }
};

FarmClient::FarmClient(const std::string& address, const ClientSecurity& security)
    : impl_(new Impl) {
  impl_->address = address;
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  impl_->tls = !security.caFile.empty();
  impl_->channel = makeClientChannel(address, security, args, &impl_->setupError);
  if (impl_->channel) impl_->stub = v1::ClientApi::NewStub(impl_->channel);
}

FarmClient::~FarmClient() = default;

Status FarmClient::connect(double seconds) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  const auto deadline = std::chrono::system_clock::now() +
                        std::chrono::duration_cast<std::chrono::system_clock::duration>(
                            std::chrono::duration<double>(seconds));
  if (!impl_->channel->WaitForConnected(deadline)) {
    // A failed TLS handshake looks the same from here as no listener: name both.
    return {StatusCode::kUnavailable,
            "cannot reach the coordinator at " + impl_->address +
                (impl_->tls ? " (is farm-coordinator running there, does its certificate verify "
                              "against --tls-ca and name the host dialled, and does it accept "
                              "this client's certificate?)"
                            : " (is farm-coordinator running there? if it serves TLS, pass "
                              "--tls-ca)")};
  }
  return Status::ok();
}

Status FarmClient::submit(const Submission& submission, std::string* jobId, SubmitStats* stats) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  const LocalBundle& bundle = submission.bundle;
  // Every blob by hash, with where to read it: identical files are sent once.
  std::map<std::string, std::string> localByHash;
  v1::SubmitJobRequest first;
  v1::JobHeader* header = first.mutable_header();
  *header->mutable_settings() = toProto(submission.settings);
  header->set_scene_path(bundle.scenePath);
  header->set_name(submission.name.empty() ? bundle.scenePath : submission.name);
  for (size_t i = 0; i < bundle.manifest.size(); ++i) {
    const BundleEntry& e = bundle.manifest[i];
    v1::BundleFile* f = header->mutable_manifest()->add_files();
    f->set_path(e.path);
    f->set_size(e.size);
    f->set_hash(e.hash);
    localByHash.emplace(e.hash, bundle.localPaths[i]);
  }
  if (!submission.referencePath.empty()) {
    std::string hash, error;
    uint64_t size = 0;
    if (!sha256File(submission.referencePath, &hash, &size, &error)) {
      return Status::invalidArgument(error);
    }
    header->mutable_reference()->set_path("reference.exr");
    header->mutable_reference()->set_size(size);
    header->mutable_reference()->set_hash(hash);
    localByHash.emplace(hash, submission.referencePath);
  }

  v1::MissingBlobsRequest missingRequest;
  for (const auto& [hash, path] : localByHash) missingRequest.add_hashes(hash);
  v1::MissingBlobsResponse missing;
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kUnaryDeadline);
    grpc::Status s = impl_->stub->MissingBlobs(&context, missingRequest, &missing);
    if (!s.ok()) return impl_->fail(s);
  }

  SubmitStats local;
  local.filesTotal = localByHash.size();
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kTransferDeadline);
  v1::SubmitJobResponse response;
  auto writer = impl_->stub->SubmitJob(&context, &response);
  bool open = writer->Write(first);
  std::string buffer;
  for (const std::string& hash : missing.missing_hashes()) {
    auto it = localByHash.find(hash);
    if (it == localByHash.end() || !open) continue;
    std::ifstream in(it->second, std::ios::binary);
    if (!in) return Status::invalidArgument("cannot read '" + it->second + "'");
    uint64_t offset = 0;
    for (;;) {
      buffer.resize(kMaxChunkBytes);
      in.read(buffer.data(), std::streamsize(buffer.size()));
      buffer.resize(size_t(in.gcount()));
      if (buffer.empty()) break;
      v1::SubmitJobRequest chunk;
      chunk.mutable_chunk()->set_hash(hash);
      chunk.mutable_chunk()->set_offset(offset);
      chunk.mutable_chunk()->set_data(buffer);
      offset += buffer.size();
      if (!(open = writer->Write(chunk))) break;
    }
    ++local.filesUploaded;
    local.bytesUploaded += offset;
  }
  writer->WritesDone();
  grpc::Status s = writer->Finish();
  if (!s.ok()) return impl_->fail(s);
  *jobId = response.job_id();
  local.bundleHash = response.bundle_hash();
  if (stats) *stats = local;
  return Status::ok();
}

Status FarmClient::progress(const std::string& jobId, uint32_t errorSeriesFrom, JobProgress* out) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  v1::GetProgressRequest request;
  request.set_job_id(jobId);
  request.set_error_series_from(errorSeriesFrom);
  v1::JobProgress response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kUnaryDeadline);
  grpc::Status s = impl_->stub->GetProgress(&context, request, &response);
  if (!s.ok()) return impl_->fail(s);
  fromProto(response, out);
  return Status::ok();
}

Status FarmClient::watch(const std::string& jobId, double intervalSeconds,
                         const std::function<bool(const JobProgress&)>& onProgress) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  v1::WatchJobRequest request;
  request.set_job_id(jobId);
  request.set_interval_ms(uint32_t(std::clamp(intervalSeconds, 0.1, 10.0) * 1000));
  grpc::ClientContext context;  // no deadline: a watch lasts as long as the job
  auto reader = impl_->stub->WatchJob(&context, request);
  v1::JobProgress message;
  bool more = true;
  while (more && reader->Read(&message)) {
    JobProgress progress;
    fromProto(message, &progress);
    more = onProgress(progress);
  }
  if (!more) {
    context.TryCancel();
    reader->Finish();
    return Status::ok();
  }
  grpc::Status s = reader->Finish();
  if (!s.ok()) return impl_->fail(s);
  return Status::ok();
}

Status FarmClient::fetchImage(const std::string& jobId, bool wait, const std::string& path) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  v1::FetchImageRequest request;
  request.set_job_id(jobId);
  request.set_wait(wait);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kTransferDeadline);
  auto reader = impl_->stub->FetchImage(&context, request);
  const std::string partial = path + ".partial";
  std::ofstream out(partial, std::ios::binary | std::ios::trunc);
  if (!out) return Status::invalidArgument("cannot write '" + partial + "'");
  v1::ImageChunk chunk;
  uint64_t received = 0, total = 0;
  bool ordered = true;
  while (reader->Read(&chunk)) {
    if (chunk.offset() != received) ordered = false;
    out.write(chunk.data().data(), std::streamsize(chunk.data().size()));
    received += chunk.data().size();
    total = chunk.total_size();
  }
  grpc::Status s = reader->Finish();
  out.close();
  if (!s.ok() || !ordered || received != total || !out) {
    std::remove(partial.c_str());
    if (!s.ok()) return impl_->fail(s);
    if (!out) return Status::invalidArgument("cannot write '" + path + "'");
    return Status::internal("the image arrived incomplete (" + std::to_string(received) + " of " +
                            std::to_string(total) + " bytes)");
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    std::remove(partial.c_str());
    return Status::invalidArgument("cannot write '" + path + "'");
  }
  return Status::ok();
}

Status FarmClient::cancel(const std::string& jobId, JobPhase* phase) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  v1::CancelJobRequest request;
  request.set_job_id(jobId);
  v1::CancelJobResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kUnaryDeadline);
  grpc::Status s = impl_->stub->CancelJob(&context, request, &response);
  if (!s.ok()) return impl_->fail(s);
  if (phase) *phase = fromProto(response.phase());
  return Status::ok();
}

Status FarmClient::list(std::vector<JobProgress>* jobs) {
  if (!impl_->stub) return {StatusCode::kInvalidArgument, impl_->setupError};
  v1::ListJobsResponse response;
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + kUnaryDeadline);
  grpc::Status s = impl_->stub->ListJobs(&context, v1::ListJobsRequest(), &response);
  if (!s.ok()) return impl_->fail(s);
  jobs->clear();
  for (const v1::JobSummary& j : response.jobs()) {
    JobProgress p;
    p.jobId = j.job_id();
    p.phase = fromProto(j.phase());
    p.fraction = j.fraction();
    p.name = j.name();
    std::string ignored;
    farm::fromProto(j.algorithm(), &p.settings.algorithm, &ignored);
    p.elapsedSeconds = j.elapsed_seconds();
    p.error = j.error();
    jobs->push_back(std::move(p));
  }
  return Status::ok();
}

}  // namespace farm
