#pragma once
// Numbers both ends of the wire must agree on.
#include <cstddef>
#include <cstdint>

namespace farm {

// Bumped whenever farm.proto changes incompatibly; RegisterWorker rejects a mismatch.
// 2: sparse and compressed flushes; 3: batches (FlushHeader.entries); 4: mlt's seen emission
// (ChainSpec.seen_emission_every), which a worker of 3 would drop and render the light twice;
// 5: RenderSettings.shading_normals, which a worker of 4 would drop and render the scene's
// convention where the job overrides it; 6: a single flush is a batch of one (FlushHeader holds
// its entry in `entries`, where a worker of 5 sends it in the header's own fields); 7: pixel
// allocations (ChainSpec.pixel_allocation), which a worker of 6 would drop and sample uniformly;
// 8: an allocation travels once per worker (ChainSpec.pixel_allocation_hash, ChainLease's bytes),
// which a worker of 7 would not find in its work unit
inline constexpr uint32_t kProtocolVersion = 8;

// Pixel allocations a worker keeps and names in a lease request (LeaseChainsRequest.
// pixel_allocations_held): a job has one, so this many jobs at once share a worker without
// their allocations travelling again.
inline constexpr int kMaxHeldAllocations = 16;

// gRPC message size limit, set explicitly on servers and channels (the library default of 4 MiB
// is implicit and asymmetric between send and receive).
inline constexpr int kMaxMessageBytes = 16 * 1024 * 1024;

// Bulk data travels in chunks no larger than this: well under kMaxMessageBytes with room for
// the envelope, and small enough that a stalled stream is noticed quickly.
inline constexpr size_t kMaxChunkBytes = 1024 * 1024;
// Flushes in one batch (FlushHeader.entries): a worker sums at most one flush a chain it runs.
inline constexpr size_t kMaxBatchEntries = 4096;

// `farm submit` leaves larger files out of a scene bundle (they are almost never scene data).
inline constexpr uint64_t kMaxBundleFileBytes = 256ull * 1024 * 1024;

// Largest blob the coordinator accepts in an upload (a bundle file or a reference image).
inline constexpr uint64_t kMaxBlobBytes = kMaxBundleFileBytes;

// A scene bundle's files and their total size: what one submit may ask the coordinator to store
// (with --max-jobs, this bounds the disk that accepted jobs can take). A scene's folder past
// these is almost always the wrong folder (a home directory), not a scene.
inline constexpr size_t kMaxBundleFiles = 10000;
inline constexpr uint64_t kMaxBundleBytes = 4ull * 1024 * 1024 * 1024;

}  // namespace farm
