#pragma once
// farm-coordinator --http HOST:PORT: a small live web page and Prometheus metrics, read-only.
//
//   /                          the page: jobs with phase, progress and ETA, and the workers; a
//                              job's view (#/job/ID) with its preview, error curve, settings
//                              and plan, refreshed every second by the page itself
//   /api/jobs                  every job's progress (JSON, as `farm status --json`)
//   /api/jobs/ID               one job's, with its error series
//   /api/jobs/ID/preview.png   the image as it stands (404 before any work arrived)
//   /api/workers               the registered workers: chains held, work accepted, last contact
//   /metrics                   the same figures in the Prometheus text format
//
// With a submit token, every request must carry it ("Authorization: Bearer TOKEN", or HTTP
// basic authentication with the token as the password, which a browser asks for). When the
// coordinator serves TLS, so does the page (HTTPS with the same certificate and key; no client
// certificate is asked of a browser: the token is the page's lock).
// cpp-httplib stays in http_service.cpp.
#include <memory>
#include <string>

namespace farm {

class Coordinator;
class CallGuard;
struct ServerSecurity;

class HttpService {
 public:
  // Listens on `address` (HOST:PORT; port 0 picks one). `guard` (may be null: no token) is the
  // gRPC listener's and must outlive the service. HTTPS when `security` names a certificate
  // and key (the coordinator's own). Null with *error when it cannot listen or the certificate
  // cannot be used.
  static std::unique_ptr<HttpService> start(const std::string& address, Coordinator* coordinator,
                                            const CallGuard* guard, const ServerSecurity& security,
                                            std::string* error);
  virtual ~HttpService() = default;
  virtual int port() const = 0;
  virtual bool https() const = 0;
  virtual void stop() = 0;
};

}  // namespace farm
