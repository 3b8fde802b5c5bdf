#pragma once
// The coordinator's content-addressed store: one file per blob (scene files, reference images)
// named by its SHA-256, and the manifests of the bundles submitted so far. Identical files are
// stored once, whatever job or path they came with, so a re-submit uploads nothing new.
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "coordinator/status.h"
#include "proto/bundle_manifest.h"
#include "proto/sha256.h"

namespace farm {

class BlobStore {
 public:
  // Receives one blob's bytes in order; commit() checks size and hash and then makes the blob
  // visible atomically (a crash or a bad upload never leaves a wrong blob under a hash).
  class Writer {
   public:
    ~Writer();
    Status append(uint64_t offset, const std::string& bytes);
    uint64_t received() const { return received_; }
    bool complete() const { return received_ == size_; }
    Status commit();

   private:
    friend class BlobStore;
    Writer(BlobStore* store, std::string hash, uint64_t size, std::string label);
    BlobStore* store_;
    std::string hash_, label_, tempPath_;
    uint64_t size_, received_ = 0;
    std::ofstream out_;
    Sha256 digest_;
    bool committed_ = false;
  };

  // Creates `dir` (and dir/blobs, dir/bundles) if needed.
  explicit BlobStore(std::string dir);

  bool has(const std::string& hash) const;
  std::string pathOf(const std::string& hash) const;
  // `label` names the blob in messages (e.g. its path in the bundle).
  Status beginWrite(const std::string& hash, uint64_t size, const std::string& label,
                    std::unique_ptr<Writer>* writer);

  // Remembers a bundle's manifest; returns its hash.
  std::string registerBundle(const BundleManifest& manifest);
  bool findBundle(const std::string& bundleHash, BundleManifest* manifest) const;
  // Lays the bundle's files out under dir/bundles/<hash>/ (hard links to the blobs where the
  // file system allows, copies otherwise) and returns that directory.
  Status materialize(const std::string& bundleHash, std::string* root);

 private:
  std::string dir_;
  mutable std::mutex mutex_;
  std::map<std::string, BundleManifest> bundles_;
  uint64_t tempCounter_ = 0;
};

}  // namespace farm
