#include "coordinator/blob_store.h"

#include <filesystem>
#include <system_error>

namespace farm {
namespace fs = std::filesystem;

BlobStore::BlobStore(std::string dir) : dir_(std::move(dir)) {
  fs::create_directories(fs::path(dir_) / "blobs");
  fs::create_directories(fs::path(dir_) / "bundles");
  fs::create_directories(fs::path(dir_) / "incoming");
}

bool BlobStore::has(const std::string& hash) const {
  if (!isSha256Hex(hash)) return false;
  std::error_code ec;
  return fs::is_regular_file(pathOf(hash), ec);
}

std::string BlobStore::pathOf(const std::string& hash) const {
  return (fs::path(dir_) / "blobs" / hash).string();
}

Status BlobStore::beginWrite(const std::string& hash, uint64_t size, const std::string& label,
                             std::unique_ptr<Writer>* writer) {
  if (!isSha256Hex(hash)) {
    return Status::invalidArgument("blob '" + label + "' has a malformed hash");
  }
  writer->reset(new Writer(this, hash, size, label));
  if (!(*writer)->out_) {
    writer->reset();
    return Status::internal("cannot create a temporary file under " + dir_ + "/incoming");
  }
  return Status::ok();
}

BlobStore::Writer::Writer(BlobStore* store, std::string hash, uint64_t size, std::string label)
    : store_(store), hash_(std::move(hash)), label_(std::move(label)), size_(size) {
  uint64_t n;
  {
    std::lock_guard<std::mutex> lock(store_->mutex_);
    n = ++store_->tempCounter_;
  }
  tempPath_ = (fs::path(store_->dir_) / "incoming" / (hash_ + "." + std::to_string(n))).string();
  out_.open(tempPath_, std::ios::binary | std::ios::trunc);
}

BlobStore::Writer::~Writer() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    fs::remove(tempPath_, ec);
  }
}

Status BlobStore::Writer::append(uint64_t offset, const std::string& bytes) {
  if (offset != received_) {
    return Status::invalidArgument("chunk of '" + label_ + "' at offset " + std::to_string(offset) +
                                   ", expected offset " + std::to_string(received_) +
                                   " (chunks must arrive in order)");
  }
  if (bytes.size() > size_ - received_) {
    return Status::invalidArgument("chunks of '" + label_ + "' exceed its declared size of " +
                                   std::to_string(size_) + " bytes");
  }
  out_.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out_) return Status::internal("cannot write blob '" + label_ + "' to disk");
  digest_.update(bytes);
  received_ += bytes.size();
  return Status::ok();
}

Status BlobStore::Writer::commit() {
  if (received_ != size_) {
    return Status::invalidArgument("'" + label_ + "' ended after " + std::to_string(received_) +
                                   " of its " + std::to_string(size_) + " bytes");
  }
  std::string actual = digest_.hexDigest();
  if (actual != hash_) {
    return Status::invalidArgument("checksum mismatch for '" + label_ + "': declared sha256 " +
                                   hash_ + ", received bytes hash to " + actual);
  }
  out_.close();
  if (!out_) return Status::internal("cannot write blob '" + label_ + "' to disk");
  std::error_code ec;
  fs::rename(tempPath_, store_->pathOf(hash_), ec);  // atomic: readers see all or nothing
  if (ec) return Status::internal("cannot store blob '" + label_ + "': " + ec.message());
  committed_ = true;
  return Status::ok();
}

std::string BlobStore::registerBundle(const BundleManifest& manifest) {
  std::string hash = bundleHash(manifest);
  std::lock_guard<std::mutex> lock(mutex_);
  bundles_.emplace(hash, manifest);
  return hash;
}

bool BlobStore::findBundle(const std::string& bundleHash, BundleManifest* manifest) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = bundles_.find(bundleHash);
  if (it == bundles_.end()) return false;
  if (manifest) *manifest = it->second;
  return true;
}

Status BlobStore::materialize(const std::string& bundleHash, std::string* root) {
  BundleManifest manifest;
  if (!findBundle(bundleHash, &manifest)) {
    return Status::notFound("unknown scene bundle " + bundleHash);
  }
  fs::path dir = fs::path(dir_) / "bundles" / bundleHash;
  *root = dir.string();
  std::lock_guard<std::mutex> lock(mutex_);  // two jobs of one bundle: lay it out once
  // The marker sits beside the directory, not in it, so no bundle file can collide with it.
  const fs::path marker = fs::path(dir_) / "bundles" / (bundleHash + ".complete");
  std::error_code ec;
  if (fs::exists(marker, ec)) return Status::ok();
  for (const BundleEntry& entry : manifest) {
    if (!has(entry.hash)) {
      return Status::failedPrecondition("bundle file '" + entry.path + "' is not in the store");
    }
    fs::path target = dir / entry.path;
    fs::create_directories(target.parent_path(), ec);
    fs::remove(target, ec);
    fs::create_hard_link(pathOf(entry.hash), target, ec);
    if (ec) {
      ec.clear();
      fs::copy_file(pathOf(entry.hash), target, fs::copy_options::overwrite_existing, ec);
      if (ec) {
        return Status::internal("cannot lay out '" + entry.path + "': " + ec.message());
      }
    }
  }
  std::ofstream(marker) << bundleHash << "\n";
  return Status::ok();
}

}  // namespace farm
