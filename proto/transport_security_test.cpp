// The parts of transport security that need no network: which addresses count as loopback (the
// coordinator refuses to expose anything else without TLS and tokens) and what a token file
// must hold.
#include "proto/transport_security.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/test_support.h"

namespace farm {
namespace {

TEST(TransportSecurity, LoopbackAddresses) {
  for (const char* a :
       {"127.0.0.1:5000", "127.3.2.1:1", "localhost:80", "[::1]:7000", "::1", "127.0.0.1"}) {
    EXPECT_TRUE(isLoopbackAddress(a)) << a;
  }
  for (const char* a :
       {"0.0.0.0:5000", "10.0.0.1:5000", "[::]:5000", "example.com:1", "128.0.0.1:1",
        "127.0.0.256:1", "localhost.example.com:1", "127.0.0:1", "[::2]:1", ""}) {
    EXPECT_FALSE(isLoopbackAddress(a)) << a;
  }
}

TEST(TransportSecurity, TokenFiles) {
  testing::ScratchDir scratch("tokens");
  auto token = [&](const std::string& contents, std::string* out, std::string* error) {
    const std::string path = scratch / "token";
    std::ofstream(path, std::ios::binary) << contents;
    return readTokenFile(path, out, error);
  };
  std::string t, error;
  EXPECT_TRUE(token("0123456789abcdef0123\r\nsecond line ignored\n", &t, &error)) << error;
  EXPECT_EQ(t, "0123456789abcdef0123");
  EXPECT_FALSE(token("short\n", &t, &error));
  EXPECT_NE(error.find("16 to 4096"), std::string::npos) << error;
  EXPECT_FALSE(token("0123456789 abcdef0123\n", &t, &error));
  EXPECT_NE(error.find("printable ASCII"), std::string::npos) << error;
  EXPECT_FALSE(token("0123456789abcdef\x01", &t, &error));
  EXPECT_FALSE(token(std::string(5000, 'a'), &t, &error));
  EXPECT_FALSE(token("", &t, &error));
  EXPECT_FALSE(readTokenFile(scratch / "absent", &t, &error));
  EXPECT_NE(error.find("cannot read token file"), std::string::npos) << error;
}

}  // namespace
}  // namespace farm
