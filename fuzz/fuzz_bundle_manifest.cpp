// A bundle manifest as it arrives in a SubmitJob header (protobuf bytes): decoded, checked
// for hostile paths (absolute, '..', backslashes, NUL, duplicates), sizes and hashes, and
// hashed - what the coordinator and the worker both do before a byte touches the disk.
#include <string>

#include "fuzz/fuzz_target.h"
#include "proto/bundle_manifest.h"
#include "proto/farm.pb.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  farm::v1::BundleManifest message;
  if (!message.ParseFromArray(data, int(size))) {
    // Not a manifest: the bytes as one path.
    farm::checkRelativePath(std::string(reinterpret_cast<const char*>(data), size));
    return 0;
  }
  farm::BundleManifest manifest;
  for (const farm::v1::BundleFile& f : message.files()) {
    manifest.push_back({f.path(), f.size(), f.hash()});
  }
  if (farm::checkManifest(manifest).empty()) farm::bundleHash(manifest);
  return 0;
}
