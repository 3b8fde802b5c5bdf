#pragma once
// The coordinator on the network: farm.v1.ClientApi and farm.v1.WorkerApi over gRPC, plus the
// standard health and reflection services. Every RPC checks its input and answers a status
// whose message says what was wrong. gRPC stays inside grpc_service.cpp.
#include <memory>
#include <string>

#include "proto/transport_security.h"

namespace farm {

class Coordinator;

class CoordinatorServer {
 public:
  // Listens on `address` (HOST:PORT; port 0 picks a free one) with the TLS and tokens that
  // `security` names (proto/transport_security.h). Null with *error on failure: a file that
  // cannot be read, a listener that `security` would leave exposed, an address in use.
  static std::unique_ptr<CoordinatorServer> start(const std::string& address,
                                                  Coordinator* coordinator,
                                                  const ServerSecurity& security,
                                                  std::string* error);
  // Plaintext and no tokens (loopback only): for tests.
  static std::unique_ptr<CoordinatorServer> start(const std::string& address,
                                                  Coordinator* coordinator, std::string* error);
  virtual ~CoordinatorServer() = default;
  virtual int port() const = 0;
  // What protects the listener, for the log: "TLS; tokens for submit and work".
  virtual std::string security() const = 0;
  // The listener's token checks, for the web page (coordinator/http_service.h).
  virtual const CallGuard* guard() const = 0;
  // Stops accepting calls and ends those in flight (after a short grace period).
  virtual void shutdown() = 0;
};

// A plaintext listener with nothing but grpc.health.v1.Health (no jobs, images or tokens to
// protect): for probes that cannot speak TLS or carry a token, such as Kubernetes' gRPC probes.
class HealthServer {
 public:
  static std::unique_ptr<HealthServer> start(const std::string& address, std::string* error);
  virtual ~HealthServer() = default;
  virtual int port() const = 0;
  virtual void shutdown() = 0;
};

}  // namespace farm
