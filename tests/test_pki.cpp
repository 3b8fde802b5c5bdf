#include "tests/test_pki.h"

#include <unistd.h>

#include <chrono>
#include <fstream>

#include "tests/test_support.h"

namespace farm::testing {

TestPki makeTestPki(const std::string& dir, const std::vector<std::string>& ips) {
  TestPki pki;
  auto at = [&](const std::string& name) { return dir + "/" + name; };
  pki.caCert = at("ca.pem");
  pki.serverCert = at("server.pem");
  pki.serverKey = at("server.key");
  pki.clientCert = at("client.pem");
  pki.clientKey = at("client.key");
  pki.rogueCert = at("rogue.pem");
  pki.rogueKey = at("rogue.key");
  pki.submitToken = at("submit.token");
  pki.workToken = at("work.token");
  pki.wrongToken = at("wrong.token");

  std::string san = "subjectAltName=DNS:localhost";
  for (const std::string& ip : ips) san += ",IP:" + ip;
  std::ofstream(at("server.ext")) << san << "\n";
  std::string openssl;
  for (const char* path : {"/usr/bin/openssl", "/bin/openssl", "/usr/local/bin/openssl"}) {
    if (::access(path, X_OK) == 0) openssl = path;
  }
  if (openssl.empty()) {
    pki.problem = "the openssl command is not installed (deploy/install-deps.sh installs it)";
    return pki;
  }
  const std::vector<std::vector<std::string>> commands = {
      {openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", at("ca.key"), "-out",
       pki.caCert, "-days", "2", "-subj", "/CN=farm test CA"},
      {openssl, "req", "-newkey", "rsa:2048", "-nodes", "-keyout", pki.serverKey, "-out",
       at("server.csr"), "-subj", "/CN=localhost"},
      {openssl, "x509", "-req", "-in", at("server.csr"), "-CA", pki.caCert, "-CAkey", at("ca.key"),
       "-CAcreateserial", "-out", pki.serverCert, "-days", "2", "-extfile", at("server.ext")},
      {openssl, "req", "-newkey", "rsa:2048", "-nodes", "-keyout", pki.clientKey, "-out",
       at("client.csr"), "-subj", "/CN=farm test worker"},
      {openssl, "x509", "-req", "-in", at("client.csr"), "-CA", pki.caCert, "-CAkey", at("ca.key"),
       "-CAcreateserial", "-out", pki.clientCert, "-days", "2"},
      {openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", pki.rogueKey, "-out",
       pki.rogueCert, "-days", "2", "-subj", "/CN=localhost"},
  };
  for (const auto& command : commands) {
    CommandResult r = runCommand(command, std::chrono::seconds(60), dir);
    if (r.exitCode != 0) {
      pki.problem = "`openssl " + command[1] + "` failed: " + r.err;
      return pki;
    }
  }
  std::ofstream(pki.submitToken) << "submit-0123456789abcdef0123456789abcdef\n";
  std::ofstream(pki.workToken) << "work-fedcba9876543210fedcba9876543210\n";
  std::ofstream(pki.wrongToken) << "wrong-00000000000000000000000000000000\n";
  return pki;
}

}  // namespace farm::testing
