#include "server/auth.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace demcal::server {

bool is_loopback(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address.rfind("localhost:", 0) == 0 ||
         address.rfind("[::1]", 0) == 0 || address.rfind("ipv4:127.", 0) == 0;
}

grpc::Status authorize(const grpc::ServerContext& context, const std::string& token) {
  if (token.empty()) return grpc::Status::OK;
  const auto& md = context.client_metadata();
  const auto it = md.find("authorization");
  const std::string expected = "Bearer " + token;
  if (it != md.end()) {
    const std::string_view got(it->second.data(), it->second.size());
    // Constant-time comparison: the time taken does not tell how much of the token matched.
    unsigned diff = got.size() == expected.size() ? 0u : 1u;
    for (std::size_t i = 0; i < expected.size(); ++i)
      diff |=
          static_cast<unsigned>(i < got.size() ? got[i] : 0) ^ static_cast<unsigned>(expected[i]);
    if (diff == 0) return grpc::Status::OK;
  }
  return {grpc::StatusCode::UNAUTHENTICATED, "missing or wrong bearer token"};
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
