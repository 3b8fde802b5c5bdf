#pragma once
// Certificates and tokens for tests of a secured farm, made with the openssl command line (the
// real tool a user would use): a CA; a server certificate it signs for localhost and the given
// IP addresses; a client certificate it signs; a rogue self-signed certificate that no CA of
// ours signs; and two tokens.
#include <string>
#include <vector>

namespace farm::testing {

struct TestPki {
  std::string caCert;                  // the CA both sides trust
  std::string serverCert, serverKey;   // signed by the CA, for localhost and `ips`
  std::string clientCert, clientKey;   // signed by the CA
  std::string rogueCert, rogueKey;     // self-signed: verifies against nothing of ours
  std::string submitToken, workToken;  // token files
  std::string wrongToken;              // a well-formed token that is neither
  std::string problem;                 // empty when all were made
};

// Writes the files into `dir` (which must exist).
TestPki makeTestPki(const std::string& dir, const std::vector<std::string>& ips = {"127.0.0.1"});

}  // namespace farm::testing
