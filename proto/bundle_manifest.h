#pragma once
// A scene bundle as a list of content-addressed files: what `farm submit` uploads, what the
// coordinator stores, and what a worker fetches and caches by the bundle's hash. Network-free.
#include <cstdint>
#include <string>
#include <vector>

namespace farm {

struct BundleEntry {
  std::string path;  // relative to the bundle's root, '/'-separated
  uint64_t size = 0;
  std::string hash;  // SHA-256 of the contents, lowercase hex
};

using BundleManifest = std::vector<BundleEntry>;

// Content address of a whole bundle: SHA-256 over the entries sorted by path, so the same files
// give the same hash whatever order they were listed in.
std::string bundleHash(const BundleManifest& manifest);

// Empty when `path` is a safe relative path (no absolute path, no '..' or '.' component, no
// empty component, no backslash or NUL), else what is wrong with it. Both ends check: a bundle
// must never write outside its own directory.
std::string checkRelativePath(const std::string& path);

// Empty when every entry has a safe, unique path, a well-formed hash and a size within
// kMaxBlobBytes, and there are at most kMaxBundleFiles of them adding up to at most
// kMaxBundleBytes; else one line saying what is wrong.
std::string checkManifest(const BundleManifest& manifest);

}  // namespace farm
