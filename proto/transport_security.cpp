#include "proto/transport_security.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/support/client_interceptor.h>
#include <openssl/bio.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "proto/sha256.h"

namespace farm {
namespace {

constexpr char kAuthorization[] = "authorization";
constexpr char kBearer[] = "Bearer ";
constexpr size_t kMinTokenChars = 16;
constexpr size_t kMaxTokenChars = 4096;
constexpr size_t kMaxPemBytes = 1 << 20;
constexpr int kClientKeepaliveMs = 30000;

bool readSmallFile(const std::string& path, const char* what, std::string* text,
                   std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = std::string("cannot read ") + what + " '" + path + "'";
    return false;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  *text = buffer.str();
  if (text->size() > kMaxPemBytes) {
    *error = std::string(what) + " '" + path + "' is larger than 1 MiB";
    return false;
  }
  return true;
}

struct BioDeleter {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct X509Deleter {
  void operator()(X509* x) const { X509_free(x); }
};
struct KeyDeleter {
  void operator()(EVP_PKEY* k) const { EVP_PKEY_free(k); }
};

// The first certificate in `pem`, or null. Checked here so that a wrong file gets an error that
// names it, not a failed handshake on the far side.
std::unique_ptr<X509, X509Deleter> firstCertificate(const std::string& pem) {
  std::unique_ptr<BIO, BioDeleter> bio(BIO_new_mem_buf(pem.data(), int(pem.size())));
  if (!bio) return nullptr;
  return std::unique_ptr<X509, X509Deleter>(
      PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
}

bool readCertificates(const std::string& path, const char* what, std::string* pem,
                      std::string* error) {
  if (!readSmallFile(path, what, pem, error)) return false;
  auto cert = firstCertificate(*pem);
  if (!cert) {
    *error = std::string(what) + " '" + path + "' holds no PEM certificate";
    return false;
  }
  if (X509_cmp_current_time(X509_get0_notAfter(cert.get())) < 0) {
    *error = std::string(what) + " '" + path + "' has expired";
    return false;
  }
  return true;
}

// A certificate chain and the private key of its first certificate.
bool readKeyPair(const std::string& certPath, const std::string& keyPath, std::string* certPem,
                 std::string* keyPem, std::string* error) {
  if (certPath.empty() != keyPath.empty()) {
    *error = "a certificate needs its key and a key its certificate (give both files)";
    return false;
  }
  if (!readCertificates(certPath, "certificate", certPem, error)) return false;
  if (!readSmallFile(keyPath, "private key", keyPem, error)) return false;
  std::unique_ptr<BIO, BioDeleter> bio(BIO_new_mem_buf(keyPem->data(), int(keyPem->size())));
  std::unique_ptr<EVP_PKEY, KeyDeleter> key(
      bio ? PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr) : nullptr);
  if (!key) {
    *error = "private key '" + keyPath + "' holds no unencrypted PEM private key";
    return false;
  }
  auto cert = firstCertificate(*certPem);
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    *error = "private key '" + keyPath + "' does not belong to certificate '" + certPath + "'";
    return false;
  }
  return true;
}

// Adds the bearer token to every call's initial metadata. An interceptor rather than call
// credentials: gRPC sends call credentials only over TLS, and a token also guards a loopback
// listener in plaintext.
class TokenInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit TokenInterceptor(const std::string* header) : header_(header) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
      methods->GetSendInitialMetadata()->emplace(kAuthorization, *header_);
    }
    methods->Proceed();
  }

 private:
  const std::string* header_;
};

class TokenInterceptorFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
 public:
  explicit TokenInterceptorFactory(std::string token) : header_(kBearer + std::move(token)) {}
  grpc::experimental::Interceptor* CreateClientInterceptor(
      grpc::experimental::ClientRpcInfo*) override {
    return new TokenInterceptor(&header_);
  }

 private:
  std::string header_;  // lives as long as the channel, which owns this factory
};

}  // namespace

const char* roleName(Role role) {
  return role == Role::kSubmit ? "submit" : "work";
}

bool readTokenFile(const std::string& path, std::string* token, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot read token file '" + path + "'";
    return false;
  }
  std::string line;
  std::getline(in, line);
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  if (line.size() < kMinTokenChars || line.size() > kMaxTokenChars) {
    *error = "token file '" + path + "': its first line must hold a token of 16 to 4096 " +
             "characters (for example from `openssl rand -hex 32`)";
    return false;
  }
  for (char c : line) {
    if (c <= ' ' || c > '~') {
      *error = "token file '" + path + "': the token may hold printable ASCII only, no spaces";
      return false;
    }
  }
  *token = line;
  return true;
}

bool isLoopbackAddress(const std::string& address) {
  std::string host = address;
  if (!host.empty() && host.front() == '[') {
    const size_t close = host.find(']');
    host = close == std::string::npos ? host : host.substr(1, close - 1);
  } else if (std::count(host.begin(), host.end(), ':') == 1) {
    host = host.substr(0, host.find(':'));
  }
  if (host == "localhost" || host == "::1") return true;
  // 127.0.0.0/8, written as four decimal octets.
  int octets[4];
  char tail = 0;
  if (std::sscanf(host.c_str(), "%d.%d.%d.%d%c", &octets[0], &octets[1], &octets[2], &octets[3],
                  &tail) != 4) {
    return false;
  }
  for (int o : octets) {
    if (o < 0 || o > 255) return false;
  }
  return octets[0] == 127;
}

std::shared_ptr<grpc::Channel> makeClientChannel(const std::string& address,
                                                 const ClientSecurity& security,
                                                 const grpc::ChannelArguments& args,
                                                 std::string* error) {
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (security.caFile.empty()) {
    if (!security.certFile.empty() || !security.keyFile.empty()) {
      *error = "a client certificate needs TLS: give the coordinator's CA too (--tls-ca)";
      return nullptr;
    }
    credentials = grpc::InsecureChannelCredentials();
  } else {
    grpc::SslCredentialsOptions options;
    if (!readCertificates(security.caFile, "CA file", &options.pem_root_certs, error)) {
      return nullptr;
    }
    if (!security.certFile.empty() || !security.keyFile.empty()) {
      if (!readKeyPair(security.certFile, security.keyFile, &options.pem_cert_chain,
                       &options.pem_private_key, error)) {
        return nullptr;
      }
    }
    credentials = grpc::SslCredentials(options);
  }
  // Keepalive: a coordinator that vanished behind a NAT or a dropped link is noticed within
  // about 40 s (a ping every 30 s, 10 s to answer), not after TCP's minutes; the server allows
  // pings this often (transport_security.h, serverKeepalive).
  grpc::ChannelArguments withKeepalive = args;
  withKeepalive.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, kClientKeepaliveMs);
  withKeepalive.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  withKeepalive.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  withKeepalive.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
  if (!security.tokenFile.empty()) {
    std::string token;
    if (!readTokenFile(security.tokenFile, &token, error)) return nullptr;
    interceptors.push_back(std::make_unique<TokenInterceptorFactory>(std::move(token)));
  }
  return grpc::experimental::CreateCustomChannelWithInterceptors(
      address, credentials, withKeepalive, std::move(interceptors));
}

struct CallGuard::Impl {
  std::shared_ptr<grpc::ServerCredentials> credentials;
  bool tls = false, mutual = false, exposed = false;
  // SHA-256 of each role's token (empty: none asked). Compared in constant time, digest to
  // digest, so that neither the token's bytes nor its length leak through timing.
  std::string submitDigest, workDigest;
};

CallGuard::CallGuard() : impl_(new Impl) {}
CallGuard::~CallGuard() = default;

std::unique_ptr<CallGuard> CallGuard::load(const std::string& address,
                                           const ServerSecurity& security, std::string* error) {
  std::unique_ptr<CallGuard> guard(new CallGuard);
  Impl& g = *guard->impl_;
  if (!security.certFile.empty() || !security.keyFile.empty()) {
    grpc::SslServerCredentialsOptions options;
    grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
    if (!readKeyPair(security.certFile, security.keyFile, &pair.cert_chain, &pair.private_key,
                     error)) {
      return nullptr;
    }
    options.pem_key_cert_pairs.push_back(pair);
    if (!security.clientCaFile.empty()) {
      if (!readCertificates(security.clientCaFile, "client CA file", &options.pem_root_certs,
                            error)) {
        return nullptr;
      }
      options.client_certificate_request =
          GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
      g.mutual = true;
    }
    g.credentials = grpc::SslServerCredentials(options);
    g.tls = true;
  } else if (!security.clientCaFile.empty()) {
    *error = "a client CA asks callers for certificates over TLS: give --tls-cert and --tls-key";
    return nullptr;
  } else {
    g.credentials = grpc::InsecureServerCredentials();
  }
  std::string submitToken, workToken;
  if (!security.submitTokenFile.empty() &&
      !readTokenFile(security.submitTokenFile, &submitToken, error)) {
    return nullptr;
  }
  if (!security.workTokenFile.empty() &&
      !readTokenFile(security.workTokenFile, &workToken, error)) {
    return nullptr;
  }
  if (!submitToken.empty() && submitToken == workToken) {
    *error =
        "the submit and work tokens are the same; each role needs its own token, or a "
        "worker could submit jobs";
    return nullptr;
  }
  if (!submitToken.empty()) g.submitDigest = sha256Hex(submitToken);
  if (!workToken.empty()) g.workDigest = sha256Hex(workToken);

  g.exposed = !isLoopbackAddress(address);
  if (g.exposed && !security.insecure) {
    if (!g.tls) {
      *error = "refusing to listen on " + address +
               " in plaintext: anyone on the network could read the jobs, images and tokens. "
               "Give --tls-cert and --tls-key, listen on loopback, or pass --insecure";
      return nullptr;
    }
    if (g.submitDigest.empty() || g.workDigest.empty()) {
      *error = "refusing to listen on " + address + " without " +
               std::string(g.submitDigest.empty() ? "--submit-token-file" : "") +
               (g.submitDigest.empty() && g.workDigest.empty() ? " and " : "") +
               (g.workDigest.empty() ? "--work-token-file" : "") +
               ": anyone who can reach it could submit jobs or pose as a worker. Give both "
               "token files, listen on loopback, or pass --insecure";
      return nullptr;
    }
  }
  return guard;
}

void serverKeepalive(grpc::ServerBuilder* builder) {
  // Ping idle clients every 60 s and drop those that do not answer in 20 s (a worker host
  // that died without closing its connection), and accept the clients' own pings every 30 s
  // (kClientKeepaliveMs) without calls in flight: below the default 5 minutes gRPC would
  // answer them with GOAWAY "too_many_pings".
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 60000);
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  builder->AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder->AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                              kClientKeepaliveMs / 2);
  builder->AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
}

std::shared_ptr<grpc::ServerCredentials> CallGuard::credentials() const {
  return impl_->credentials;
}

bool CallGuard::tls() const {
  return impl_->tls;
}

CallCheck CallGuard::check(const grpc::ServerContext& context, Role role) const {
  const auto& metadata = context.client_metadata();
  auto it = metadata.find(kAuthorization);
  if (it == metadata.end()) return checkHeader("", false, role);
  return checkHeader(std::string(it->second.data(), it->second.size()), true, role);
}

bool CallGuard::asksToken(Role role) const {
  return !(role == Role::kSubmit ? impl_->submitDigest : impl_->workDigest).empty();
}

CallCheck CallGuard::checkHeader(const std::string& header, bool present, Role role) const {
  const std::string& wanted = role == Role::kSubmit ? impl_->submitDigest : impl_->workDigest;
  const std::string& other = role == Role::kSubmit ? impl_->workDigest : impl_->submitDigest;
  if (wanted.empty()) return {};
  const std::string flag =
      role == Role::kSubmit ? "farm's --token-file" : "farm-worker's --token-file";
  if (!present) {
    return {CallCheck::Code::kUnauthenticated,
            std::string("this coordinator's ") + (role == Role::kSubmit ? "client" : "worker") +
                " API needs the " + roleName(role) + " token and the call carried none (pass " +
                flag + ")"};
  }
  const size_t prefix = sizeof(kBearer) - 1;
  const std::string digest =
      header.compare(0, prefix, kBearer) == 0 ? sha256Hex(header.substr(prefix)) : std::string();
  auto same = [&](const std::string& a) {
    return !a.empty() && digest.size() == a.size() &&
           CRYPTO_memcmp(digest.data(), a.data(), a.size()) == 0;
  };
  if (same(wanted)) return {};
  if (same(other)) {
    return {CallCheck::Code::kPermissionDenied,
            std::string("a ") + roleName(role == Role::kSubmit ? Role::kWork : Role::kSubmit) +
                " token does not open the " + (role == Role::kSubmit ? "client" : "worker") +
                " API; it needs the " + roleName(role) + " token"};
  }
  return {CallCheck::Code::kUnauthenticated,
          std::string("the call's token is not this coordinator's ") + roleName(role) + " token"};
}

std::string CallGuard::describe() const {
  std::string text = impl_->tls       ? (impl_->mutual ? "TLS with client certificates" : "TLS")
                     : impl_->exposed ? "plaintext on the network (--insecure)"
                                      : "plaintext (loopback only)";
  const bool submit = !impl_->submitDigest.empty(), work = !impl_->workDigest.empty();
  if (submit && work) return text + "; tokens for submit and work";
  if (!submit && !work) return text + "; no tokens: anyone who can connect may submit and work";
  return text + "; a token for " + (submit ? "submit" : "work") + " only: anyone who can " +
         "connect may " + (submit ? "work" : "submit");
}

std::string CallGuard::exposureWarning() const {
  if (!impl_->exposed) return "";
  if (!impl_->tls)
    return "--insecure: listening beyond loopback in plaintext: jobs, images and any token cross "
           "the network readable";
  if (impl_->submitDigest.empty() || impl_->workDigest.empty())
    return "--insecure: listening beyond loopback without both tokens";
  return "";
}

}  // namespace farm
