#pragma once
// The client side of farm.v1.ClientApi, for `farm submit/status/fetch/cancel/list` and tests.
// Every call has a deadline; failures come back as a Status whose message a person can act on.
// gRPC stays in farm_client.cpp.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cli/scene_bundle.h"
#include "coordinator/job.h"
#include "coordinator/status.h"
#include "proto/transport_security.h"

namespace farm {

struct Submission {
  RenderSettings settings;
  LocalBundle bundle;
  std::string referencePath;  // optional EXR, uploaded beside the bundle
  std::string name;           // shown by `farm list`
};

struct SubmitStats {
  size_t filesTotal = 0, filesUploaded = 0;
  uint64_t bytesUploaded = 0;
  std::string bundleHash;
};

class FarmClient {
 public:
  // `security`: the TLS roots, client certificate and token to present (none: plaintext).
  // A file that cannot be used makes every call fail with a message naming it.
  explicit FarmClient(const std::string& address, const ClientSecurity& security = {});
  ~FarmClient();

  // Checks that the coordinator answers within `seconds`.
  Status connect(double seconds = 5);
  // Uploads what the coordinator is missing and starts the job.
  Status submit(const Submission& submission, std::string* jobId, SubmitStats* stats = nullptr);
  Status progress(const std::string& jobId, uint32_t errorSeriesFrom, JobProgress* out);
  // Streams the job's progress every `intervalSeconds` (0.1 to 10) until it ends; each
  // message's error series holds only the samples not passed before. `onProgress` returning
  // false stops the watch (the job goes on). Ok once the job has ended (whatever its phase).
  Status watch(const std::string& jobId, double intervalSeconds,
               const std::function<bool(const JobProgress&)>& onProgress);
  // Downloads the final EXR to `path` (written beside and renamed, so a failure leaves no
  // partial file). wait=false: FailedPrecondition unless the job is done.
  Status fetchImage(const std::string& jobId, bool wait, const std::string& path);
  Status cancel(const std::string& jobId, JobPhase* phase);
  Status list(std::vector<JobProgress>* jobs);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace farm
