#include "proto/bundle_manifest.h"

#include <algorithm>
#include <set>

#include "proto/sha256.h"
#include "proto/wire_limits.h"

namespace farm {

std::string bundleHash(const BundleManifest& manifest) {
  std::vector<const BundleEntry*> sorted;
  for (const BundleEntry& e : manifest) sorted.push_back(&e);
  std::sort(sorted.begin(), sorted.end(),
            [](const BundleEntry* a, const BundleEntry* b) { return a->path < b->path; });
  Sha256 hash;
  for (const BundleEntry* e : sorted) {
    // NUL cannot occur in a checked path, so the encoding is unambiguous.
    hash.update(e->path);
    hash.update("\0", 1);
    hash.update(std::to_string(e->size));
    hash.update("\0", 1);
    hash.update(e->hash);
    hash.update("\n", 1);
  }
  return hash.hexDigest();
}

std::string checkRelativePath(const std::string& path) {
  if (path.empty()) return "empty file path";
  if (path.size() > 1024) return "file path longer than 1024 characters";
  if (path.front() == '/') return "absolute file path '" + path + "' (must be relative)";
  if (path.find('\\') != std::string::npos || path.find('\0') != std::string::npos) {
    return "file path '" + path + "' contains a backslash or NUL";
  }
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    std::string component = path.substr(start, end - start);
    if (component.empty() || component == "." || component == "..") {
      return "file path '" + path + "' has an empty, '.' or '..' component";
    }
    start = end + 1;
  }
  return "";
}

std::string checkManifest(const BundleManifest& manifest) {
  if (manifest.size() > kMaxBundleFiles) {
    return "the bundle lists " + std::to_string(manifest.size()) + " files (limit " +
           std::to_string(kMaxBundleFiles) + ")";
  }
  std::set<std::string> seen;
  uint64_t total = 0;
  for (const BundleEntry& e : manifest) {
    std::string problem = checkRelativePath(e.path);
    if (!problem.empty()) return problem;
    if (!seen.insert(e.path).second) return "file '" + e.path + "' is listed twice";
    if (!isSha256Hex(e.hash)) {
      return "file '" + e.path + "' has hash '" + e.hash.substr(0, 80) +
             "' (expected 64 lowercase hex digits of SHA-256)";
    }
    if (e.size > kMaxBlobBytes) {
      return "file '" + e.path + "' is " + std::to_string(e.size) + " bytes (limit " +
             std::to_string(kMaxBlobBytes) + ")";
    }
    total += e.size;  // each at most kMaxBlobBytes, at most kMaxBundleFiles of them: no overflow
  }
  if (total > kMaxBundleBytes) {
    return "the bundle's files add up to " + std::to_string(total) + " bytes (limit " +
           std::to_string(kMaxBundleBytes) + ")";
  }
  return "";
}

}  // namespace farm
