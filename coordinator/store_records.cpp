#include "coordinator/store_records.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "proto/convert.h"
#include "proto/coordinator_store.pb.h"
#include "proto/sha256.h"
#include "proto/zstd_frame.h"

namespace farm::store {
namespace fs = std::filesystem;

int phaseCode(JobPhase phase) {
  switch (phase) {
    case JobPhase::kSubmitted:
    case JobPhase::kLoadingScene:
    case JobPhase::kBootstrapping:
      return 1;  // prepared again after a restart
    case JobPhase::kRendering:
    case JobPhase::kFinishing:
      return 2;  // resumed from the log
    case JobPhase::kDone:
      return 3;
    case JobPhase::kFailed:
      return 4;
    case JobPhase::kCancelled:
      return 5;
  }
  return 1;
}

bool phaseFromCode(int64_t code, JobPhase* phase) {
  switch (code) {
    case 1:
      *phase = JobPhase::kSubmitted;
      return true;
    case 2:
      *phase = JobPhase::kRendering;
      return true;
    case 3:
      *phase = JobPhase::kDone;
      return true;
    case 4:
      *phase = JobPhase::kFailed;
      return true;
    case 5:
      *phase = JobPhase::kCancelled;
      return true;
  }
  return false;
}

std::string encodeBundle(const BundleManifest& manifest) {
  farm::v1::BundleManifest m;
  for (const BundleEntry& e : manifest) {
    farm::v1::BundleFile* f = m.add_files();
    f->set_path(e.path);
    f->set_size(e.size);
    f->set_hash(e.hash);
  }
  return m.SerializeAsString();
}

bool decodeBundle(const std::string& bytes, BundleManifest* manifest) {
  farm::v1::BundleManifest m;
  if (!m.ParseFromString(bytes)) return false;
  for (const farm::v1::BundleFile& f : m.files())
    manifest->push_back({f.path(), f.size(), f.hash()});
  return true;
}

std::string encodeSpec(const JobSpec& spec) {
  v1::JobRecord r;
  *r.mutable_settings() = toProto(spec.settings);
  r.set_scene_path(spec.scenePath);
  r.set_reference_path(spec.referencePath);
  r.set_name(spec.name);
  r.set_bundle_hash(spec.bundleHash);
  r.set_bundle_scene_path(spec.bundleScenePath);
  r.set_bundle_root(spec.bundleRoot);
  return r.SerializeAsString();
}

bool decodeSpec(const std::string& bytes, JobSpec* spec, std::string* error) {
  v1::JobRecord r;
  if (!r.ParseFromString(bytes)) {
    *error = "unreadable job record";
    return false;
  }
  if (!fromProto(r.settings(), &spec->settings, error)) return false;
  spec->scenePath = r.scene_path();
  spec->referencePath = r.reference_path();
  spec->name = r.name();
  spec->bundleHash = r.bundle_hash();
  spec->bundleScenePath = r.bundle_scene_path();
  spec->bundleRoot = r.bundle_root();
  return true;
}

std::string encodePlan(const JobPlan& plan) {
  v1::PlanRecord r;
  r.set_normalization(plan.bootstrap.normalization);
  r.set_normalization_std_error(plan.bootstrap.normalizationStdError);
  r.set_candidates(plan.bootstrap.candidates);
  r.set_non_zero_candidates(plan.bootstrap.nonZeroCandidates);
  r.set_bootstrap_seconds(plan.bootstrap.seconds);
  r.set_abandoned_connections(plan.bootstrap.abandonedConnections);
  // A chain names its allocation by hash, and the planned settings hold its bytes once; an
  // allocation they do not hold (none is made so today) keeps its bytes in the chain's record.
  const std::string planned = plan.plannedSettings
                                  ? pixelAllocationHash(plan.plannedSettings->pixelAllocation)
                                  : std::string();
  for (const ChainSpec& chain : plan.chains) {
    farm::v1::ChainSpec* c = r.add_chains();
    *c = toProto(chain);
    if (!c->pixel_allocation_hash().empty() && c->pixel_allocation_hash() != planned) {
      c->clear_pixel_allocation_hash();
      c->set_pixel_allocation(chain.pixelAllocation->encode());
    }
  }
  r.set_planned_work(plan.plannedWork);
  r.set_width(plan.width);
  r.set_height(plan.height);
  r.set_load_seconds(plan.loadSeconds);
  for (const std::string& w : plan.warnings) r.add_warnings(w);
  for (const std::string& line : plan.renderPlan) r.add_render_plan(line);
  if (plan.plannedSettings) *r.mutable_planned_settings() = toProto(*plan.plannedSettings);
  return r.SerializeAsString();
}

bool decodePlan(const std::string& bytes, JobPlan* plan, std::string* error) {
  v1::PlanRecord r;
  if (!r.ParseFromString(bytes)) {
    *error = "unreadable plan record";
    return false;
  }
  plan->bootstrap.normalization = r.normalization();
  plan->bootstrap.normalizationStdError = r.normalization_std_error();
  plan->bootstrap.candidates = r.candidates();
  plan->bootstrap.nonZeroCandidates = r.non_zero_candidates();
  plan->bootstrap.seconds = r.bootstrap_seconds();
  plan->bootstrap.abandonedConnections = r.abandoned_connections();
  if (r.has_planned_settings()) {
    RenderSettings settings;
    if (!fromProto(r.planned_settings(), &settings, error)) return false;
    plan->plannedSettings = settings;
  }
  // The chains name the planned settings' allocation, stored once for all of them.
  std::shared_ptr<const PixelAllocation> allocation;
  std::string allocationHash, allocationBytes;
  if (plan->plannedSettings && plan->plannedSettings->pixelAllocation) {
    allocation = plan->plannedSettings->pixelAllocation;
    allocationBytes = allocation->encode();
    allocationHash = sha256Hex(allocationBytes);
  }
  const AllocationLookup lookup = [&](const std::string& hash) {
    return hash == allocationHash ? allocation : nullptr;
  };
  for (const farm::v1::ChainSpec& c : r.chains()) {
    ChainSpec chain;
    if (!fromProto(c, &chain, error, lookup)) return false;
    // A record of protocol 7 holds a copy in every chain: they share the planned one.
    if (allocation && !c.pixel_allocation().empty() && c.pixel_allocation() == allocationBytes) {
      chain.pixelAllocation = allocation;
    }
    plan->chains.push_back(std::move(chain));
  }
  plan->plannedWork = r.planned_work();
  plan->width = r.width();
  plan->height = r.height();
  if (plan->width <= 0 || plan->height <= 0) {
    *error = "plan record with an empty film";
    return false;
  }
  plan->loadSeconds = r.load_seconds();
  plan->warnings.assign(r.warnings().begin(), r.warnings().end());
  plan->renderPlan.assign(r.render_plan().begin(), r.render_plan().end());
  return true;
}

namespace {

// A record's film (`film`'s width, height and splats), as it travels (proto/splat_codec.h).
void encodeFilm(const ChainFlush& film, const EncodedSplats* wire, v1::FlushRecord* r) {
  r->set_width(film.width);
  r->set_height(film.height);
  EncodedSplats encoded;
  if (!wire) encoded = encodeSplats(film.splats);
  const EncodedSplats& splats = wire ? *wire : encoded;
  r->set_splats(splats.bytes);
  r->set_sparse(splats.sparse);
  r->set_compressed(splats.compressed);
  r->set_raw_splat_bytes(splats.rawBytes);
}

}  // namespace

// A batch: its film, and each entry as it travelled.
std::string encodeBatch(const FlushBatch& batch, const EncodedSplats* wire) {
  v1::FlushRecord r;
  encodeFilm(batch.film, wire, &r);
  for (const ChainFlush& entry : batch.entries) toProto(entry, 0, r.add_flushes());
  return r.SerializeAsString();
}

// Either kind of record as a batch (a single flush: a batch of one).
bool decodeRecord(const std::string& bytes, FlushBatch* batch, std::string* error) {
  v1::FlushRecord r;
  if (!r.ParseFromString(bytes) || r.width() <= 0 || r.height() <= 0) {
    *error = "unreadable flush record";
    return false;
  }
  if (!r.flushes().empty()) {
    for (const farm::v1::FlushEntry& e : r.flushes()) batch->entries.push_back(fromProto(e));
  } else if (!r.entries().empty()) {
    // The older forms (schema version 3 and before): see FlushRecord.
    for (const v1::FlushRecord& e : r.entries()) batch->entries.push_back(chainFlushFrom(e));
  } else {
    batch->entries.push_back(chainFlushFrom(r));
  }
  batch->epochs.assign(batch->entries.size(), 0);
  ChainFlush& film = batch->film;
  film.width = r.width();
  film.height = r.height();
  EncodedSplats splats;
  splats.bytes = r.splats();
  splats.sparse = r.sparse();
  splats.compressed = r.compressed();
  splats.rawBytes = r.raw_splat_bytes();
  std::string problem;
  if (!decodeSplats(splats, size_t(r.width()) * size_t(r.height()) * 3, &film.splats, &problem)) {
    *error = "the record of flush " + std::to_string(batch->entries.front().flushIndex) +
             " of chain " + std::to_string(batch->entries.front().chainIndex) + ": " + problem;
    return false;
  }
  return true;
}

std::string encodeCheckpoint(const SplatAggregator::Snapshot& s,
                             const std::vector<ChainScheduler::ChainSnapshot>& chains,
                             const std::string& sumsFile) {
  v1::CheckpointRecord r;
  r.set_sums_file(sumsFile);
  r.set_sums_layout(1);
  r.set_work_done(s.workDone);
  r.set_prior_work(s.priorWork);
  r.set_rejected_nan(s.rejected.nan);
  r.set_rejected_infinite(s.rejected.infinite);
  r.set_rejected_negative(s.rejected.negative);
  r.set_rays(s.rays);
  r.set_accepted_flushes(s.acceptedFlushes);
  for (int64_t w : s.groupWork) r.add_group_work(w);
  for (const MutationTally& t : s.tallies) toProto(t, r.add_tallies());
  if (s.largeSteps.count != 0) toProto(s.largeSteps, r.mutable_large_steps());
  for (size_t i = 0; i < chains.size(); ++i) {
    v1::ChainRecord* c = r.add_chains();
    c->set_resume_state(chains[i].resumeState);
    c->set_mutations_done(chains[i].mutationsDone);
    c->set_next_flush_index(chains[i].nextFlushIndex);
    c->set_finished(chains[i].finished);
  }
  return r.SerializeAsString();
}

std::string encodeFilms(const SplatAggregator& sums) {
  const std::vector<double>& image = sums.sums();
  std::string frames = zstdCompress(image.data(), image.size() * sizeof(double));
  for (uint32_t g = 0; g < SplatAggregator::groupFilmCount(sums.groups()); ++g) {
    const std::vector<float>& film = sums.groupSums(g);
    frames += zstdCompress(film.data(), film.size() * sizeof(float));
  }
  return frames;
}

bool decodeCheckpoint(const std::string& bytes, size_t values, uint32_t groups,
                      const std::string& logDir, SplatAggregator::Snapshot* s,
                      std::vector<ChainScheduler::ChainSnapshot>* chains, std::string* sumsFile,
                      std::string* error) {
  v1::CheckpointRecord r;
  if (!r.ParseFromString(bytes)) {
    *error = "unreadable checkpoint record";
    return false;
  }
  *sumsFile = r.sums_file();
  if (sumsFile->find('/') != std::string::npos) {
    *error = "a checkpoint names the file '" + *sumsFile + "'";
    return false;
  }
  if (values > 0) {
    std::string frames = r.sums_zstd();
    if (!sumsFile->empty()) {
      const std::string path = (fs::path(logDir) / *sumsFile).string();
      std::ifstream in(path, std::ios::binary);
      frames.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
      if (!in.good() && !in.eof()) {
        *error = "cannot read the checkpoint's film " + path;
        return false;
      }
    }
    const size_t groupFilms = SplatAggregator::groupFilmCount(groups);
    s->sums.assign(values, 0.0);
    s->groupSums.clear();
    for (size_t g = 0; g < groupFilms; ++g) s->groupSums.emplace_back(values);
    bool read = false;
    if (r.sums_layout() == 0) {  // a group's film at a time: the image is their sum in order
      auto addGroup = [&](const char* film, size_t g) {
        for (size_t i = 0; i < values; ++i) {
          double v;
          std::memcpy(&v, film + i * sizeof(double), sizeof(double));
          s->sums[i] += v;
          if (groupFilms > 0) s->groupSums[g][i] = float(v);
        }
      };
      read = zstdDecompressChunks(frames, values * sizeof(double), std::max<uint32_t>(groups, 1),
                                  addGroup);
    } else if (r.sums_layout() == 1) {
      std::vector<std::pair<void*, size_t>> outs = {{s->sums.data(), values * sizeof(double)}};
      for (std::vector<float>& g : s->groupSums)
        outs.emplace_back(g.data(), values * sizeof(float));
      read = zstdDecompressFrames(frames, outs);
    } else {
      *error = "a checkpoint of film layout " + std::to_string(r.sums_layout()) +
               " (this coordinator reads 0 and 1)";
      return false;
    }
    if (!read) {
      *error = "the checkpoint's film " +
               (sumsFile->empty() ? std::string("in the database") : *sumsFile) +
               " is missing, corrupt or of another film size";
      return false;
    }
  }
  s->workDone = r.work_done();
  s->priorWork = r.prior_work();
  s->rejected.nan = r.rejected_nan();
  s->rejected.infinite = r.rejected_infinite();
  s->rejected.negative = r.rejected_negative();
  s->rays = r.rays();
  s->acceptedFlushes = r.accepted_flushes();
  s->groupWork.assign(r.group_work().begin(), r.group_work().end());
  for (const farm::v1::MutationTally& t : r.tallies()) s->tallies.push_back(fromProto(t));
  s->largeSteps = largeStepsFromProto(r.large_steps());
  for (const v1::ChainRecord& c : r.chains()) {
    chains->push_back({c.resume_state(), c.mutations_done(), c.next_flush_index(), c.finished()});
    s->nextFlush.push_back(c.next_flush_index());
  }
  return true;
}

}  // namespace farm::store
