#pragma once
// The coordinator store's records (proto/coordinator_store.proto) to and from the job's types:
// what the database and the flush log hold, apart from where and how they hold it
// (coordinator/job_store.h). A record that does not decode answers false with *error.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/render/render_job.h"
#include "coordinator/chain_scheduler.h"
#include "coordinator/job.h"
#include "coordinator/splat_aggregator.h"
#include "proto/bundle_manifest.h"
#include "proto/splat_codec.h"

namespace farm {

// What the bootstrap decided, as much of it as a restarted job needs.
struct JobPlan {
  BootstrapResult bootstrap;  // the figures only; the seeds travel in the chains
  std::vector<ChainSpec> chains;
  int64_t plannedWork = 0;
  int width = 0, height = 0;
  double loadSeconds = 0;
  std::vector<std::string> warnings;
  std::vector<std::string> renderPlan;  // the plan's lines (RenderPlan::describe)
  // The settings the plan left the job with (auto's algorithm, mlt's mix); absent in records
  // from before plans, whose job's own settings hold.
  std::optional<RenderSettings> plannedSettings;
};

namespace store {

// A job's phase as the jobs table stores it (codes that stay when the enum changes).
int phaseCode(JobPhase phase);
bool phaseFromCode(int64_t code, JobPhase* phase);

// A scene bundle's manifest (the bundles table).
std::string encodeBundle(const BundleManifest& manifest);
bool decodeBundle(const std::string& bytes, BundleManifest* manifest);

std::string encodeSpec(const JobSpec& spec);
bool decodeSpec(const std::string& bytes, JobSpec* spec, std::string* error);
std::string encodePlan(const JobPlan& plan);
bool decodePlan(const std::string& bytes, JobPlan* plan, std::string* error);

// One record of the flush log: a batch's film once (as it travelled, `wire`, or encoded from
// batch.film when null), then each entry as it travelled (the wire's FlushEntry). A single flush
// is a batch of one. Records of schema version 3 and before (FlushRecord's older forms) decode
// the same way. Decoded batches carry epoch 0 for each entry.
std::string encodeBatch(const FlushBatch& batch, const EncodedSplats* wire);
bool decodeRecord(const std::string& bytes, FlushBatch* batch, std::string* error);

// The counts and resume points; the films go to `sumsFile` (beside the database) when named,
// as encodeFilms() writes them.
std::string encodeCheckpoint(const SplatAggregator::Snapshot& s,
                             const std::vector<ChainScheduler::ChainSnapshot>& chains,
                             const std::string& sumsFile = "");
// The aggregator's films, compressed as CheckpointRecord's layout 1: the image's, then each
// group's (with two or more groups).
std::string encodeFilms(const SplatAggregator& sums);
// `values` is a film's size (width*height*3) and `groups` the job's error groups, or 0 values
// for the counts a finished job keeps; the films are read from `logDir`/sums_file, in either
// layout (a layout-0 record's groups are summed into the image and kept as float).
// *sumsFile: the file the record names ("" for none).
bool decodeCheckpoint(const std::string& bytes, size_t values, uint32_t groups,
                      const std::string& logDir, SplatAggregator::Snapshot* s,
                      std::vector<ChainScheduler::ChainSnapshot>* chains, std::string* sumsFile,
                      std::string* error);

}  // namespace store
}  // namespace farm
