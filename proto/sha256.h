#pragma once
// SHA-256 (FIPS 180-4), the content address of scene files, bundles and flush payloads, by
// OpenSSL's libcrypto (already on every machine that has gRPC): its assembly runs at several
// times the speed of portable code, and a well-kept library beats our own.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

struct evp_md_ctx_st;

namespace farm {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* data, size_t size);
  void update(const std::string& bytes) { update(bytes.data(), bytes.size()); }
  // The digest as 64 lowercase hex characters. The object must not be updated afterwards
  // (until reset()).
  std::string hexDigest();
  // Starts a new digest.
  void reset();

 private:
  evp_md_ctx_st* context_;
};

std::string sha256Hex(const std::string& bytes);
// Hashes a file's contents; false (with *error naming the file) when it cannot be read.
bool sha256File(const std::string& path, std::string* hex, uint64_t* size, std::string* error);
// True for 64 lowercase hex characters: what every "hash" field on the wire must look like.
bool isSha256Hex(const std::string& text);

}  // namespace farm
