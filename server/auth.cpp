#include "server/auth.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace demcal::server {

bool is_loopback(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address.rfind("localhost:", 0) == 0 ||
         address.rfind("[::1]", 0) == 0 || address.rfind("ipv4:127.", 0) == 0;
}

namespace {

/// Whether the call's authorization header is "Bearer <token>", in time independent of how
/// much of it matches. An empty token never matches.
bool presents(const grpc::ServerContext& context, const std::string& token) {
  if (token.empty()) return false;
  const auto& md = context.client_metadata();
  const auto it = md.find("authorization");
  if (it == md.end()) return false;
  const std::string expected = "Bearer " + token;
  const std::string_view got(it->second.data(), it->second.size());
  unsigned diff = got.size() == expected.size() ? 0u : 1u;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned>(i < got.size() ? got[i] : 0) ^ static_cast<unsigned>(expected[i]);
  return diff == 0;
}

}  // namespace

grpc::Status authorize(const grpc::ServerContext& context, const Tokens& tokens, Caller caller) {
  if (tokens.empty()) return grpc::Status::OK;
  const std::string& own = caller == Caller::kWorker ? tokens.worker : tokens.client;
  const std::string& other = caller == Caller::kWorker ? tokens.client : tokens.worker;
  if (presents(context, tokens.both) || presents(context, own)) return grpc::Status::OK;
  if (presents(context, other))
    return {grpc::StatusCode::PERMISSION_DENIED,
            caller == Caller::kWorker ? "a client token cannot call the worker service"
                                      : "a worker token cannot call the campaign service"};
  return {grpc::StatusCode::UNAUTHENTICATED, "missing or wrong bearer token"};
}

std::string token_name(const grpc::ServerContext& context, const Tokens& tokens) {
  if (presents(context, tokens.both)) return "operator";
  if (presents(context, tokens.client)) return "client";
  return {};
}

namespace {
std::string read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

std::shared_ptr<grpc::ServerCredentials> server_credentials(const std::string& address,
                                                            const std::string& tls_cert,
                                                            const std::string& tls_key,
                                                            bool insecure) {
  if (!tls_cert.empty()) {
    grpc::SslServerCredentialsOptions o;
    o.pem_key_cert_pairs.push_back({read_file(tls_key), read_file(tls_cert)});
    return grpc::SslServerCredentials(o);
  }
  if (insecure) return grpc::InsecureServerCredentials();
  if (is_loopback(address)) return grpc::experimental::LocalServerCredentials(LOCAL_TCP);
  throw std::invalid_argument("listening on " + address +
                              " beyond loopback needs --tls-cert/--tls-key, or --insecure");
}

}  // namespace demcal::server
