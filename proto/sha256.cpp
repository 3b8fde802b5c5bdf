#include "proto/sha256.h"

#include <openssl/evp.h>

#include <fstream>
#include <new>
#include <stdexcept>
#include <vector>

namespace farm {

Sha256::Sha256() : context_(EVP_MD_CTX_new()) {
  if (!context_) throw std::bad_alloc();
  if (EVP_DigestInit_ex(context_, EVP_sha256(), nullptr) != 1) {
    EVP_MD_CTX_free(context_);
    throw std::runtime_error("OpenSSL cannot start a SHA-256 digest");
  }
}

void Sha256::reset() {
  if (EVP_DigestInit_ex(context_, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("OpenSSL cannot start a SHA-256 digest");
  }
}

Sha256::~Sha256() {
  EVP_MD_CTX_free(context_);
}

void Sha256::update(const void* data, size_t size) {
  if (size > 0 && EVP_DigestUpdate(context_, data, size) != 1) {
    throw std::runtime_error("OpenSSL SHA-256 update failed");
  }
}

std::string Sha256::hexDigest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(context_, digest, &length) != 1 || length != 32) {
    throw std::runtime_error("OpenSSL SHA-256 final failed");
  }
  static const char* kHex = "0123456789abcdef";
  std::string hex;
  hex.reserve(64);
  for (unsigned int i = 0; i < length; ++i) {
    hex.push_back(kHex[digest[i] >> 4]);
    hex.push_back(kHex[digest[i] & 0xf]);
  }
  return hex;
}

std::string sha256Hex(const std::string& bytes) {
  Sha256 hash;
  hash.update(bytes);
  return hash.hexDigest();
}

bool sha256File(const std::string& path, std::string* hex, uint64_t* size, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open '" + path + "' for reading";
    return false;
  }
  Sha256 hash;
  std::vector<char> buffer(1 << 16);
  uint64_t total = 0;
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    std::streamsize got = in.gcount();
    if (got > 0) {
      hash.update(buffer.data(), size_t(got));
      total += uint64_t(got);
    }
  }
  if (in.bad()) {
    *error = "error while reading '" + path + "'";
    return false;
  }
  *hex = hash.hexDigest();
  if (size) *size = total;
  return true;
}

bool isSha256Hex(const std::string& text) {
  if (text.size() != 64) return false;
  for (char c : text) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

}  // namespace farm
