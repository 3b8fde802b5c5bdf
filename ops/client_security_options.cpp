#include "ops/client_security_options.h"

#include <CLI/CLI.hpp>

namespace farm {

void addClientSecurityOptions(CLI::App* app, ClientSecurity* security, const std::string& envPrefix,
                              Role role) {
  app->add_option("--tls-ca", security->caFile,
                  "PEM CA certificates to verify the coordinator's TLS certificate against "
                  "(default: plaintext)")
      ->envname(envPrefix + "_TLS_CA");
  app->add_option("--tls-cert", security->certFile,
                  "PEM client certificate, for a coordinator that asks for one (with --tls-key)")
      ->envname(envPrefix + "_TLS_CERT");
  app->add_option("--tls-key", security->keyFile, "PEM private key of --tls-cert")
      ->envname(envPrefix + "_TLS_KEY");
  app->add_option("--token-file", security->tokenFile,
                  std::string("file whose first line is the coordinator's ") +
                      (role == Role::kSubmit ? "submit" : "work") + " token")
      ->envname(envPrefix + "_TOKEN_FILE");
}

}  // namespace farm
