#include "proto/sha256.h"

#include <gtest/gtest.h>

#include "proto/bundle_manifest.h"
#include "proto/wire_limits.h"

namespace farm {
namespace {

// FIPS 180-4 examples (NIST CSRC "SHA256.pdf") and the empty message.
TEST(Sha256, KnownDigests) {
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, IncrementalUpdatesMatchOneShot) {
  std::string text;
  for (int i = 0; i < 1000; ++i) text += char('a' + i % 26);
  for (size_t split : {0u, 1u, 55u, 56u, 63u, 64u, 65u, 500u, 999u}) {
    Sha256 hash;
    hash.update(text.substr(0, split));
    hash.update(text.substr(split));
    EXPECT_EQ(hash.hexDigest(), sha256Hex(text)) << "split at " << split;
  }
}

TEST(BundleManifest, HashIgnoresOrderAndSeesContent) {
  BundleManifest a{{"scene.xml", 3, sha256Hex("abc")}, {"mesh.obj", 1, sha256Hex("x")}};
  BundleManifest b{a[1], a[0]};
  EXPECT_EQ(bundleHash(a), bundleHash(b));
  b[0].hash = sha256Hex("y");
  EXPECT_NE(bundleHash(a), bundleHash(b));
}

TEST(BundleManifest, RejectsPathsOutsideTheBundle) {
  EXPECT_EQ(checkRelativePath("models/mesh.obj"), "");
  EXPECT_NE(checkRelativePath("/etc/passwd"), "");
  EXPECT_NE(checkRelativePath("../up.xml"), "");
  EXPECT_NE(checkRelativePath("a/../../b"), "");
  EXPECT_NE(checkRelativePath("a//b"), "");
  EXPECT_NE(checkRelativePath("a\\b"), "");
  EXPECT_NE(checkRelativePath(""), "");
  BundleManifest twice{{"a", 1, sha256Hex("a")}, {"a", 1, sha256Hex("a")}};
  EXPECT_NE(checkManifest(twice), "");
  BundleManifest badHash{{"a", 1, "ABC"}};
  EXPECT_NE(checkManifest(badHash), "");
}

// What one submit may ask the coordinator to store: at most kMaxBundleFiles files adding up to
// at most kMaxBundleBytes (each file within kMaxBlobBytes).
TEST(BundleManifestTest, BoundsTheFilesAndTheirTotal) {
  BundleManifest many;
  for (size_t i = 0; i < kMaxBundleFiles; ++i)
    many.push_back({"f" + std::to_string(i), 1, sha256Hex("x")});
  EXPECT_EQ(checkManifest(many), "");
  many.push_back({"one-more", 1, sha256Hex("x")});
  EXPECT_NE(checkManifest(many).find("10001 files"), std::string::npos) << checkManifest(many);
  BundleManifest big;
  for (uint64_t total = 0; total + kMaxBlobBytes <= kMaxBundleBytes; total += kMaxBlobBytes)
    big.push_back({"big" + std::to_string(big.size()), kMaxBlobBytes, sha256Hex("x")});
  EXPECT_EQ(checkManifest(big), "") << "exactly the limit";
  big.push_back({"last-byte", 1, sha256Hex("x")});
  EXPECT_NE(checkManifest(big).find("add up to"), std::string::npos) << checkManifest(big);
}

}  // namespace
}  // namespace farm
