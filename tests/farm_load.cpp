// farm_load: the coordinator's ingest under many workers (issue 8, part 5). It starts a real
// farm-coordinator, submits a real job over ClientApi, registers --workers simulated workers
// over WorkerApi (each with its own worker id and leases), renders --samples of their leased
// chains' first flushes with the real renderer, and then has every simulated worker upload
// those flushes (as its own chains' next flush indices) as fast as the coordinator takes them,
// until --seconds or --max-flushes. It measures what the coordinator spends: flushes/s, bytes
// on the wire per second, the coordinator process's CPU per flush (from /proc), and the upload
// latency; and it checks that the job counted every accepted flush exactly once (its work done
// is the sum of the accepted flushes' mutations), also when uploads are retried
// (--duplicate-every).
//
// Simulated workers differ from farm-worker only in that they do not render between uploads:
// the point is the coordinator's cost, not the renderer's.
//   build/bin/farm_load --algorithm pssmlt --width 1920 --height 1080 --workers 256 --seconds 20
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cli/farm_client.h"
#include "cli/scene_bundle.h"
#include "common/render/render_job.h"
#include "proto/convert.h"
#include "proto/farm.grpc.pb.h"
#include "proto/sha256.h"
#include "proto/splat_codec.h"
#include "proto/transport_security.h"
#include "proto/wire_limits.h"
#include "tests/test_pki.h"
#include "tests/test_support.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string coordinatorBin = FARM_COORDINATOR_BIN;
  std::string scene = std::string(FARM_SHARED_DIR) + "/scenes/cornell-box/scene.xml";
  std::string algorithm = "pssmlt";
  int width = 256, height = 256;
  int workers = 64;
  int chainsPerWorker = 1;
  double seconds = 10;
  int64_t maxFlushes = 0;  // 0: until --seconds
  bool durable = false;
  int connections = 8;
  int samples = 2;
  int duplicateEvery = 0;  // > 0: every Nth upload re-sends a chain's last accepted flush
  bool batch = false;      // each upload: a simulated worker's chains summed (FlushHeader.entries)
  std::string json;
  bool check = false;
  bool tls = false;  // the coordinator serves TLS with tokens, and every upload goes over it
};

// A chain held by a simulated worker, and the next flush index it uploads.
struct SimChain {
  std::string worker;
  uint32_t chain = 0;
  uint64_t epoch = 0;
  uint32_t nextFlush = 0;
  uint32_t group = 0;  // its error group: a batch holds one group's chains
};

// A real flush, encoded once; every simulated chain sends it as its own.
struct SampleFlush {
  ChainFlush flush;
  EncodedSplats splats;
  std::string checksum;
};

struct Tally {
  int64_t accepted = 0, refused = 0, mutations = 0;
  int64_t duplicates = 0;  // re-sent flushes answered DUPLICATE, as they must be
  int64_t uploads = 0;     // calls made (a batch: one for all its flushes)
  uint64_t wireBytes = 0, rawBytes = 0;
  std::vector<double> latencies;
  std::string firstError;
};

// utime + stime of a process, in seconds.
double processCpuSeconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Fields after the command name (which may hold spaces) start after the last ')'.
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime
  }
  return ticks / double(sysconf(_SC_CLK_TCK));
}

// Peak resident memory of a process (VmHWM), in MiB.
double peakResidentMiB(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0;
}

// With --tls: the CA and work token every simulated worker presents (plaintext otherwise).
ClientSecurity gWorkSecurity;

std::shared_ptr<grpc::Channel> channel(const std::string& address) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  // A connection of its own per channel, as separate worker processes would have.
  args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
  std::string error;
  auto ch = makeClientChannel(address, gWorkSecurity, args, &error);
  if (!ch) {
    std::cerr << "farm_load: " << error << "\n";
    std::exit(1);
  }
  return ch;
}

// The header, then the splat bytes in chunks, as a worker streams them.
grpc::Status sendUpload(grpc::ClientWriter<v1::UploadFlushRequest>* writer,
                        const v1::UploadFlushRequest& header, const std::string& bytes) {
  bool open = writer->Write(header);
  for (size_t at = 0; open && at < bytes.size(); at += kMaxChunkBytes) {
    v1::UploadFlushRequest chunk;
    chunk.set_splats(bytes.data() + at, std::min(kMaxChunkBytes, bytes.size() - at));
    open = writer->Write(chunk);
  }
  writer->WritesDone();
  return writer->Finish();
}

// One upload of a simulated worker's chains as a batch (a single flush: a batch of one): `film`
// is their films summed; each chain's entry carries the sample flush it replays. `back`: re-send
// the previous batch.
grpc::Status uploadBatch(v1::WorkerApi::Stub* stub, const std::string& jobId,
                         const std::vector<SimChain*>& chains, bool back,
                         const std::vector<SampleFlush>& samples, const SampleFlush& film,
                         v1::UploadFlushResponse* response) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto writer = stub->UploadFlush(&context, response);
  v1::UploadFlushRequest message;
  v1::FlushHeader* h = message.mutable_header();
  h->set_worker_id(chains.front()->worker);
  h->set_job_id(jobId);
  h->set_width(film.flush.width);
  h->set_height(film.flush.height);
  Sha256 digest;
  digest.update(film.splats.bytes);
  for (const SimChain* c : chains) {
    const ChainFlush& f = samples[c->chain % samples.size()].flush;
    toProto(f, c->epoch, h->add_entries());
    h->mutable_entries(h->entries_size() - 1)->set_flush_index(c->nextFlush - (back ? 1 : 0));
    h->mutable_entries(h->entries_size() - 1)->set_chain_index(c->chain);
    digest.update(f.state);
  }
  h->set_splat_bytes(film.splats.bytes.size());
  h->set_sparse(film.splats.sparse);
  h->set_compressed(film.splats.compressed);
  h->set_raw_splat_bytes(film.splats.rawBytes);
  h->set_checksum(digest.hexDigest());
  return sendUpload(writer.get(), message, film.splats.bytes);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

int run(const Options& o) {
  Algorithm algorithm;
  if (!parseAlgorithm(o.algorithm, &algorithm)) {
    std::cerr << "farm_load: unknown algorithm '" << o.algorithm << "'\n";
    return 2;
  }
  testing::ScratchDir scratch("farm-load");
  std::vector<std::string> argv = {o.coordinatorBin, "--listen", "127.0.0.1:0", "--lease-seconds",
                                   "3600"};
  if (o.durable) {
    argv.push_back("--data");
    argv.push_back(scratch / "data");
  }
  ClientSecurity submitSecurity;
  if (o.tls) {
    const testing::TestPki pki = testing::makeTestPki(scratch.path());
    if (!pki.problem.empty()) {
      std::cerr << "farm_load: " << pki.problem << "\n";
      return 1;
    }
    argv.insert(argv.end(),
                {"--tls-cert", pki.serverCert, "--tls-key", pki.serverKey, "--submit-token-file",
                 pki.submitToken, "--work-token-file", pki.workToken});
    gWorkSecurity = {pki.caCert, "", "", pki.workToken};
    submitSecurity = {pki.caCert, "", "", pki.submitToken};
  }
  testing::ChildProcess coordinator(argv, scratch / "coordinator.out", scratch / "coordinator.err");
  const std::string text = testing::waitForText(
      scratch / "coordinator.out", "listening on 127.0.0.1:", std::chrono::seconds(20));
  const size_t at = text.find("127.0.0.1:");
  if (at == std::string::npos) {
    std::cerr << "farm_load: the coordinator did not start:\n"
              << testing::readFile(scratch / "coordinator.err");
    return 1;
  }
  const std::string address = "127.0.0.1:" + std::to_string(std::atoi(text.c_str() + at + 10));

  // The job: a budget no load test reaches, one chain per simulated worker's slot.
  Submission submission;
  submission.settings.algorithm = algorithm;
  submission.settings.width = o.width;
  submission.settings.height = o.height;
  submission.settings.samplesPerPixel = int64_t(1) << 24;
  submission.settings.mutationsPerPixel = int64_t(1) << 24;
  submission.settings.numChains = o.workers * o.chainsPerWorker;
  submission.settings.bootstrapSamples = 1 << 16;  // Z's accuracy is not what is measured
  submission.name = "farm_load";
  std::string error;
  if (!collectSceneBundle(o.scene, &submission.bundle, &error)) {
    std::cerr << "farm_load: " << error << "\n";
    return 1;
  }
  FarmClient client(address, submitSecurity);
  std::string jobId;
  Status st = client.submit(submission, &jobId);
  if (!st.isOk()) {
    std::cerr << "farm_load: cannot submit: " << st.message() << "\n";
    return 1;
  }
  JobProgress progress;
  const Clock::time_point submitted = Clock::now();
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    st = client.progress(jobId, 0, &progress);
  } while (st.isOk() &&
           (progress.phase == JobPhase::kSubmitted || progress.phase == JobPhase::kLoadingScene ||
            progress.phase == JobPhase::kBootstrapping));
  if (!st.isOk() || progress.phase != JobPhase::kRendering) {
    std::cerr << "farm_load: the job did not start rendering: "
              << (st.isOk() ? progress.error : st.message()) << "\n";
    return 1;
  }
  std::cerr << "farm_load: job " << jobId << " rendering after "
            << std::chrono::duration<double>(Clock::now() - submitted).count() << " s\n";

  // Simulated workers register and lease their chains.
  auto control = v1::WorkerApi::NewStub(channel(address));
  std::vector<SimChain> chains;
  std::vector<ChainSpec> specs;
  RenderSettings leasedSettings;
  for (int w = 0; w < o.workers; ++w) {
    grpc::ClientContext rc;
    v1::RegisterWorkerRequest req;
    req.set_protocol_version(kProtocolVersion);
    req.set_worker_version("farm_load");
    req.set_threads(o.chainsPerWorker);
    req.add_capabilities(algorithmName(algorithm));
    req.set_host("farm_load-" + std::to_string(w));
    v1::RegisterWorkerResponse reg;
    grpc::Status s = control->RegisterWorker(&rc, req, &reg);
    if (!s.ok()) {
      std::cerr << "farm_load: cannot register: " << s.error_message() << "\n";
      return 1;
    }
    grpc::ClientContext lc;
    v1::LeaseChainsRequest lreq;
    lreq.set_worker_id(reg.worker_id());
    lreq.set_max_chains(o.chainsPerWorker);
    v1::LeaseChainsResponse leases;
    s = control->LeaseChains(&lc, lreq, &leases);
    if (!s.ok() || leases.leases_size() != o.chainsPerWorker) {
      std::cerr << "farm_load: worker " << w << " leased " << leases.leases_size() << " of "
                << o.chainsPerWorker << " chains " << s.error_message() << "\n";
      return 1;
    }
    for (const v1::ChainLease& lease : leases.leases()) {
      chains.push_back({reg.worker_id(), lease.spec().chain_index(), lease.epoch(), 0,
                        lease.spec().error_group()});
      if (int(specs.size()) < o.samples) {
        ChainSpec spec;
        if (!fromProto(lease.spec(), &spec, &error) ||
            !fromProto(lease.settings(), &leasedSettings, &error)) {
          std::cerr << "farm_load: a malformed lease: " << error << "\n";
          return 1;
        }
        specs.push_back(std::move(spec));
      }
    }
  }

  // Real flushes: the first flush of the first leased chains, rendered here.
  std::shared_ptr<Scene> scene = loadScene(o.scene, leasedSettings);
  RenderJob renderJob(scene, leasedSettings, jobId);
  std::vector<SampleFlush> samples(specs.size());
  {
    const Clock::time_point t0 = Clock::now();
    std::vector<std::thread> renderers;
    for (size_t i = 0; i < specs.size(); ++i) {
      renderers.emplace_back([&, i] {
        renderJob.runChain(specs[i], [&](ChainFlush&& f) {
          samples[i].flush = std::move(f);
          return false;
        });
      });
    }
    for (std::thread& t : renderers) t.join();
    for (SampleFlush& s : samples) {
      s.splats = encodeSplats(s.flush.splats);
      Sha256 digest;
      digest.update(s.splats.bytes);
      digest.update(s.flush.state);
      s.checksum = digest.hexDigest();
      s.flush.finished = false;
    }
    std::cerr << "farm_load: rendered " << samples.size() << " sample flushes of "
              << samples[0].flush.mutations << " "
              << (isMarkovChain(algorithm) ? "mutations" : "samples") << " in "
              << std::chrono::duration<double>(Clock::now() - t0).count() << " s\n";
  }

  // A batch's film: the sample flushes summed, as a worker sums its chains' (the density of
  // the sum is what its size depends on).
  SampleFlush batchFilm;
  if (o.batch) {
    batchFilm.flush.width = samples[0].flush.width;
    batchFilm.flush.height = samples[0].flush.height;
    std::vector<double> sum(samples[0].flush.splats.size(), 0.0);
    for (int k = 0; k < o.chainsPerWorker; ++k) {
      const ChainFlush& f = samples[size_t(k) % samples.size()].flush;
      for (size_t i = 0; i < sum.size(); ++i) sum[i] += f.splats[i];
    }
    batchFilm.flush.splats.assign(sum.begin(), sum.end());
    batchFilm.splats = encodeSplats(batchFilm.flush.splats);
  }
  // What one upload carries: a chain, or (--batch) all of a simulated worker's of one error
  // group.
  std::vector<std::vector<SimChain*>> units;
  for (SimChain& c : chains) {
    if (!o.batch || units.empty() || units.back().front()->worker != c.worker ||
        units.back().front()->group != c.group)
      units.emplace_back();
    units.back().push_back(&c);
  }

  // The load: each connection uploads for its share of the units, round robin.
  const int connections = std::max(1, std::min<int>(o.connections, int(units.size())));
  std::vector<Tally> tallies(static_cast<size_t>(connections));
  std::atomic<int64_t> sent{0};
  const double cpu0 = processCpuSeconds(coordinator.pid());
  const Clock::time_point start = Clock::now();
  const Clock::time_point end =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.seconds));
  std::vector<std::thread> threads;
  for (int k = 0; k < connections; ++k) {
    threads.emplace_back([&, k] {
      // Connected before the load, as a worker is before it flushes: a first connect that
      // fails on a busy machine would otherwise fail this connection's uploads fast (gRPC's
      // reconnect backoff) and count them as refusals.
      std::shared_ptr<grpc::Channel> ch = channel(address);
      Tally& t = tallies[size_t(k)];
      if (!ch->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(20))) {
        t.firstError = "connection " + std::to_string(k) + " could not connect in 20 s";
        ++t.refused;
        return;
      }
      auto stub = v1::WorkerApi::NewStub(ch);
      std::vector<std::vector<SimChain*>*> mine;
      for (size_t i = size_t(k); i < units.size(); i += size_t(connections)) {
        mine.push_back(&units[i]);
      }
      for (size_t n = 0; Clock::now() < end; ++n) {
        if (o.maxFlushes > 0 && sent.fetch_add(1) >= o.maxFlushes) break;
        if (o.batch) {
          std::vector<SimChain*>& unit = *mine[n % mine.size()];
          const bool resend = o.duplicateEvery > 0 && unit.front()->nextFlush > 0 &&
                              (n + 1) % size_t(o.duplicateEvery) == 0;
          v1::UploadFlushResponse response;
          const Clock::time_point t0 = Clock::now();
          grpc::Status status =
              uploadBatch(stub.get(), jobId, unit, resend, samples, batchFilm, &response);
          t.latencies.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
          ++t.uploads;
          if (resend && status.ok() && response.result() == v1::UploadFlushResponse::DUPLICATE) {
            t.duplicates += int64_t(unit.size());
          } else if (!resend && status.ok() &&
                     response.result() == v1::UploadFlushResponse::ACCEPTED) {
            t.wireBytes += batchFilm.splats.bytes.size();
            t.rawBytes += batchFilm.flush.splats.size() * sizeof(float);
            for (SimChain* c : unit) {
              ++t.accepted;
              t.mutations += samples[c->chain % samples.size()].flush.mutations;
              ++c->nextFlush;
            }
          } else {
            ++t.refused;
            if (t.firstError.empty()) {
              t.firstError = status.ok() ? "batch result " + std::to_string(int(response.result()))
                                         : status.error_message();
            }
          }
          continue;
        }
        SimChain& c = *mine[n % mine.size()]->front();
        const SampleFlush& s = samples[c.chain % samples.size()];
        v1::UploadFlushResponse response;
        // A retry of the chain's last accepted flush, as a worker that lost the answer sends.
        const bool resend =
            o.duplicateEvery > 0 && c.nextFlush > 0 && (n + 1) % size_t(o.duplicateEvery) == 0;
        const Clock::time_point t0 = Clock::now();
        grpc::Status status = uploadBatch(stub.get(), jobId, {&c}, resend, samples, s, &response);
        t.latencies.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        ++t.uploads;
        if (resend && status.ok() && response.result() == v1::UploadFlushResponse::DUPLICATE) {
          ++t.duplicates;
        } else if (!resend && status.ok() &&
                   response.result() == v1::UploadFlushResponse::ACCEPTED) {
          ++t.accepted;
          t.mutations += s.flush.mutations;
          t.wireBytes += s.splats.bytes.size();
          t.rawBytes += s.flush.splats.size() * sizeof(float);
          ++c.nextFlush;
        } else {
          ++t.refused;
          if (t.firstError.empty()) {
            t.firstError = status.ok() && response.entries_size() == 1
                               ? "result " + std::to_string(int(response.entries(0).result())) +
                                     ": " + response.entries(0).reason()
                               : status.error_message();
          }
        }
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  const double cpu = processCpuSeconds(coordinator.pid()) - cpu0;

  Tally total;
  for (Tally& t : tallies) {
    total.accepted += t.accepted;
    total.refused += t.refused;
    total.duplicates += t.duplicates;
    total.uploads += t.uploads;
    total.mutations += t.mutations;
    total.wireBytes += t.wireBytes;
    total.rawBytes += t.rawBytes;
    total.latencies.insert(total.latencies.end(), t.latencies.begin(), t.latencies.end());
    if (total.firstError.empty()) total.firstError = t.firstError;
  }
  st = client.progress(jobId, 0, &progress);
  const bool counted = st.isOk() && progress.workDone == total.mutations;
  const double rss = peakResidentMiB(coordinator.pid());
  JobPhase phase;
  client.cancel(jobId, &phase);
  coordinator.stop();

  nlohmann::json r;
  r["algorithm"] = o.algorithm;
  r["width"] = o.width;
  r["height"] = o.height;
  r["workers"] = o.workers;
  r["chains"] = chains.size();
  r["connections"] = connections;
  r["durable"] = o.durable;
  r["tls"] = o.tls;
  r["seconds"] = wall;
  r["flushes_accepted"] = total.accepted;
  r["flushes_refused"] = total.refused;
  r["duplicates_recognized"] = total.duplicates;
  r["batch"] = o.batch;
  r["uploads"] = total.uploads;
  r["uploads_per_second"] = double(total.uploads) / wall;
  r["flushes_per_second"] = double(total.accepted) / wall;
  // Per accepted upload (a batch's film once for all its flushes).
  const double acceptedUploads =
      o.batch ? double(total.accepted) / o.chainsPerWorker : double(total.accepted);
  r["wire_bytes_per_upload"] = acceptedUploads > 0 ? double(total.wireBytes) / acceptedUploads : 0;
  r["dense_bytes_per_upload"] = acceptedUploads > 0 ? double(total.rawBytes) / acceptedUploads : 0;
  r["wire_bytes_per_flush"] = total.accepted ? double(total.wireBytes) / double(total.accepted) : 0;
  r["wire_mb_per_second"] = double(total.wireBytes) / wall / 1e6;
  r["coordinator_cpu_seconds"] = cpu;
  r["coordinator_cores_busy"] = cpu / wall;
  r["coordinator_cpu_ms_per_flush"] = total.accepted ? 1e3 * cpu / double(total.accepted) : 0;
  r["coordinator_peak_rss_mib"] = rss;
  r["latency_p50_ms"] = 1e3 * percentile(total.latencies, 0.5);
  r["latency_p99_ms"] = 1e3 * percentile(total.latencies, 0.99);
  r["mutations_per_flush"] = samples[0].flush.mutations;
  r["work_done_matches"] = counted;
  std::cout << r.dump(2) << "\n";
  if (!o.json.empty()) std::ofstream(o.json) << r.dump(2) << "\n";
  if (total.refused > 0) std::cerr << "farm_load: first refusal: " << total.firstError << "\n";
  if (!counted) {
    std::cerr << "farm_load: the job counted " << progress.workDone << " "
              << "units of work for accepted flushes holding " << total.mutations << "\n";
  }
  if (o.check && (!counted || total.refused > 0 || total.accepted == 0 ||
                  (o.duplicateEvery > 0 && total.duplicates == 0))) {
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace farm

int main(int argc, char** argv) {
  farm::Options o;
  CLI::App app{
      "Load generator: a real farm-coordinator, a real job, and many simulated workers uploading "
      "real flushes over loopback. Prints the coordinator's ingest (flushes/s, MB/s, CPU per "
      "flush, latency) as JSON."};
  app.add_option("--coordinator-binary", o.coordinatorBin, "farm-coordinator to start")
      ->capture_default_str();
  app.add_option("--scene", o.scene, "scene of the job")->capture_default_str();
  app.add_option("--algorithm", o.algorithm, "pt, bdpt, pssmlt or mlt")->capture_default_str();
  app.add_option("--width", o.width, "film width")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  app.add_option("--height", o.height, "film height")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  app.add_option("--workers", o.workers, "simulated workers (one registration each)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--chains-per-worker", o.chainsPerWorker, "chains each simulated worker leases")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--seconds", o.seconds, "how long to upload")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 3600.0));
  app.add_option("--max-flushes", o.maxFlushes, "stop after this many uploads (0: no bound)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--connections", o.connections, "concurrent uploads (one TCP connection each)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  app.add_option("--samples", o.samples, "distinct real flushes rendered and replayed")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  app.add_option("--duplicate-every", o.duplicateEvery,
                 "every Nth upload re-sends a chain's last accepted flush, which must come back "
                 "DUPLICATE (0: never)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--tls", o.tls,
               "the coordinator serves TLS with a token per role (certificates made by the "
               "openssl command in the scratch directory), and every simulated worker uses them");
  app.add_flag("--durable", o.durable, "start the coordinator with --data (SQLite, synchronous)");
  app.add_flag("--batch", o.batch,
               "each upload carries all of a simulated worker's chains, their flushes summed "
               "into one film (as farm-worker --batch-window sends them)");
  app.add_option("--json", o.json, "also write the figures to this file");
  app.add_flag("--check", o.check,
               "exit 1 unless every upload was accepted and the job counted each exactly once");
  CLI11_PARSE(app, argc, argv);
  try {
    return farm::run(o);
  } catch (const std::exception& e) {
    std::cerr << "farm_load: " << e.what() << "\n";
    return 1;
  }
}
