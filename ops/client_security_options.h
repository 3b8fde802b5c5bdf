#pragma once
// The client side's TLS and token flags, the same on every program that calls a coordinator
// (farm-worker, and each `farm` command that talks to one): --tls-ca, --tls-cert, --tls-key and
// --token-file, each with an environment variable PREFIX_TLS_CA, PREFIX_TLS_CERT, PREFIX_TLS_KEY,
// PREFIX_TOKEN_FILE (proto/transport_security.h says what each does).
#include <string>

#include "proto/transport_security.h"

namespace CLI {
class App;
}

namespace farm {

// `envPrefix` is "FARM" or "FARM_WORKER"; `role` names the token the coordinator asks of this
// program ("submit" or "work").
void addClientSecurityOptions(CLI::App* app, ClientSecurity* security, const std::string& envPrefix,
                              Role role);

}  // namespace farm
