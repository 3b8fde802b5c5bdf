#pragma once
// SHA-256 (FIPS 180-4), the content address of scene files, bundles and flush payloads.
// Written here rather than pulled from OpenSSL to keep the dependency list of DESIGN.md; speed is
// ample (~200 MB/s), far below the cost of rendering what the bytes describe.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace farm {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, size_t size);
  void update(const std::string& bytes) { update(bytes.data(), bytes.size()); }
  // The digest as 64 lowercase hex characters. The object must not be updated afterwards.
  std::string hexDigest();

 private:
  void compress(const uint8_t* block);

  std::array<uint32_t, 8> state_;
  std::array<uint8_t, 64> buffer_;
  size_t buffered_ = 0;
  uint64_t totalBytes_ = 0;
};

std::string sha256Hex(const std::string& bytes);
// Hashes a file's contents; false (with *error naming the file) when it cannot be read.
bool sha256File(const std::string& path, std::string* hex, uint64_t* size, std::string* error);
// True for 64 lowercase hex characters: what every "hash" field on the wire must look like.
bool isSha256Hex(const std::string& text);

}  // namespace farm
