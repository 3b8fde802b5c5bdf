#pragma once
// Who may talk to a coordinator, and how the talk is protected: TLS on the channel (optionally
// mutual: the coordinator asks every caller for a certificate signed by its client CA), and a
// bearer token on every call, with two roles. The submit token opens farm.v1.ClientApi (submit,
// poll, fetch, cancel), the work token farm.v1.WorkerApi (lease, upload); a token of one role
// is refused by the other, so a leaked worker token cannot submit jobs or read images.
//
// The header has no gRPC in it (the CLI includes it for its flags); the credentials are built
// in transport_security.cpp, for the three programs that speak gRPC.
#include <memory>
#include <string>

namespace grpc {
class Channel;
class ServerBuilder;
class ChannelArguments;
class ServerContext;
class ServerCredentials;
}  // namespace grpc

namespace farm {

// What a client (farm, farm-worker, a test) presents to a coordinator. Files are PEM.
struct ClientSecurity {
  std::string caFile;     // roots that sign the coordinator's certificate; empty: plaintext
  std::string certFile;   // a client certificate and its key, for a coordinator that asks
  std::string keyFile;    //   for one (mutual TLS)
  std::string tokenFile;  // a bearer token on its first line; empty: no token
};

// What a coordinator asks of its callers.
struct ServerSecurity {
  std::string certFile, keyFile;  // TLS; both empty: plaintext
  std::string clientCaFile;       // with TLS: every caller presents a certificate signed by these
  std::string submitTokenFile;    // the ClientApi's token; empty: no token asked
  std::string workTokenFile;      // the WorkerApi's token
  // Listen on an address other than loopback in plaintext or without both tokens anyway.
  bool insecure = false;
};

enum class Role { kSubmit, kWork };
const char* roleName(Role role);

// A token file's first line (trailing CR and whitespace dropped): 16 to 4096 printable ASCII
// characters without spaces, since it travels as an HTTP/2 header value. False with *error.
bool readTokenFile(const std::string& path, std::string* token, std::string* error);

// True for 127.0.0.0/8, [::1] and localhost (HOST:PORT or HOST).
bool isLoopbackAddress(const std::string& address);

// A channel to `address` as `security` says: TLS when caFile is set (with a client certificate
// when certFile is), and the token on every call when tokenFile is. Null with *error naming the
// file when one cannot be read or is malformed.
std::shared_ptr<grpc::Channel> makeClientChannel(const std::string& address,
                                                 const ClientSecurity& security,
                                                 const grpc::ChannelArguments& args,
                                                 std::string* error);

// The coordinator's keepalive, matched to the clients' (makeClientChannel pings every 30 s).
void serverKeepalive(grpc::ServerBuilder* builder);

// The outcome of checking one call's token.
struct CallCheck {
  enum class Code { kOk, kUnauthenticated, kPermissionDenied };
  Code code = Code::kOk;
  std::string message;  // for the caller: what was wrong and what to pass
  bool ok() const { return code == Code::kOk; }
};

// The coordinator's side, loaded once at start and then read-only (shared by every call).
class CallGuard {
 public:
  // Null with *error when a file cannot be read, the key does not match the certificate's
  // form, the two tokens are the same, or `address` is not loopback and the listener would be
  // plaintext or tokenless without `insecure`.
  static std::unique_ptr<CallGuard> load(const std::string& address, const ServerSecurity& security,
                                         std::string* error);
  ~CallGuard();

  // TLS (mutual with a client CA) or insecure credentials for the listening port.
  std::shared_ptr<grpc::ServerCredentials> credentials() const;
  // Whether this call may use `role`'s API: always, when that role has no token; else its
  // "authorization: Bearer TOKEN" header must carry that role's token. A missing or unknown
  // token is kUnauthenticated; the other role's token is kPermissionDenied.
  CallCheck check(const grpc::ServerContext& context, Role role) const;
  // The same for an "authorization" header's value (empty: none), for the web page.
  CallCheck checkHeader(const std::string& authorization, bool present, Role role) const;
  bool asksToken(Role role) const;
  // For the log line: "TLS with client certificates; tokens for submit and work", or
  // "plaintext (loopback only); no tokens: anyone on this host may submit and work".
  std::string describe() const;
  // What --insecure let through, for a warning in the log; empty when nothing was.
  std::string exposureWarning() const;
  bool tls() const;

 private:
  CallGuard();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace farm
