#pragma once
// Translation between the wire messages of farm.proto and the renderer's plain structs. The
// renderer (common/) knows nothing of protobuf; this is the only place the two meet.
#include <functional>
#include <memory>
#include <string>

#include "common/chain/chain_spec.h"
#include "common/render/job_phase.h"
#include "common/render/job_progress.h"
#include "common/render/render_settings.h"
#include "proto/farm.pb.h"

namespace farm {

v1::Algorithm toProto(Algorithm algorithm);
// False (with *error) for ALGORITHM_UNSPECIFIED or a value this build does not know.
bool fromProto(v1::Algorithm algorithm, Algorithm* out, std::string* error);

// kLeftOut: without the pixel allocation, for messages that never use it (a lease's settings,
// whose work units name it by hash; a progress poll, whose plan lines say what it did), so that
// it is neither encoded nor sent.
enum class WithAllocation { kIncluded, kLeftOut };
v1::RenderSettings toProto(const RenderSettings& settings,
                           WithAllocation allocation = WithAllocation::kIncluded);
// Converts only; the caller still runs RenderSettings::validate().
bool fromProto(const v1::RenderSettings& message, RenderSettings* out, std::string* error);

// A work unit names its pixel allocation by hash (pixelAllocationHash); the bytes travel once
// per job and worker, beside the work units (farm.proto's ChainLease, the store's plan record).
v1::ChainSpec toProto(const ChainSpec& spec);
// The allocation a hash names among those that came with the work unit; null when none did.
using AllocationLookup =
    std::function<std::shared_ptr<const PixelAllocation>(const std::string& hash)>;
// A work unit that names an allocation `lookup` does not know is refused (*error says which).
bool fromProto(const v1::ChainSpec& message, ChainSpec* out, std::string* error,
               const AllocationLookup& lookup = {});
// The SHA-256 (lowercase hex) of the allocation's byte form: its name on the wire. Remembers the
// last allocation this thread asked about, since every lease of a job asks about the same one.
std::string pixelAllocationHash(const std::shared_ptr<const PixelAllocation>& allocation);
// An allocation's bytes that arrived beside its work units, decoded and checked against the hash
// they were sent as.
bool decodePixelAllocation(const std::string& bytes, const std::string& hash,
                           std::shared_ptr<const PixelAllocation>* out, std::string* error);
// A chain's flush as an upload's entry (everything but its film; the upload carries the film) and
// back.
void toProto(const ChainFlush& flush, uint64_t epoch, v1::FlushEntry* entry);
void toProto(const LargeStepSums& sums, v1::LargeStepSums* out);
// A chain's tally of one kind of proposal (a flush's, a job's, the store's records alike).
void toProto(const MutationTally& tally, v1::MutationTally* out);
MutationTally fromProto(const v1::MutationTally& tally);
LargeStepSums largeStepsFromProto(const v1::LargeStepSums& sums);
ChainFlush fromProto(const v1::FlushEntry& entry);
// A chain's flush (without its film) from any message that names its fields as FlushEntry does:
// the wire's entry, and the coordinator store's records of schema version 3 and before
// (coordinator/store_records.cpp), whose field numbers differ.
template <class Message>
ChainFlush chainFlushFrom(const Message& m) {
  ChainFlush f;
  f.chainIndex = m.chain_index();
  f.flushIndex = m.flush_index();
  f.mutations = m.mutations();
  f.rejected.nan = m.rejected_nan();
  f.rejected.infinite = m.rejected_infinite();
  f.rejected.negative = m.rejected_negative();
  f.rays = m.rays();
  f.state = m.state();
  f.finished = m.finished();
  for (const v1::MutationTally& t : m.tallies()) f.tallies.push_back(fromProto(t));
  f.largeSteps = largeStepsFromProto(m.large_steps());
  return f;
}

v1::JobPhase toProto(JobPhase phase);
// PHASE_UNSPECIFIED and values this build does not know read as submitted.
JobPhase fromProto(v1::JobPhase phase);

// A job's progress, as the coordinator answers status polls and a client reads them. A client
// reads settings it cannot convert (from a newer coordinator) as the defaults.
void toProto(const JobProgress& progress, v1::JobProgress* out);
void fromProto(const v1::JobProgress& message, JobProgress* out);

}  // namespace farm
