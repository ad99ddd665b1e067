#include "rpc/channel.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace demcal::rpc {

namespace {
bool loopback(const std::string& a) {
  return a.rfind("127.", 0) == 0 || a.rfind("localhost:", 0) == 0 || a.rfind("[::1]", 0) == 0;
}
}  // namespace

int checkpoint_message_limit(double max_checkpoint_mb) {
  constexpr double kMiB = 1024.0 * 1024.0;
  return static_cast<int>(std::min((max_checkpoint_mb + 1.0) * kMiB, 2147483647.0));
}

std::shared_ptr<grpc::Channel> make_channel(const ChannelOptions& o) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(checkpoint_message_limit(kMaxCheckpointMb));
  // Reconnect quickly after a coordinator restart.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  if (!o.tls_ca.empty()) {
    std::ifstream in(o.tls_ca);
    if (!in) throw std::runtime_error("cannot read " + o.tls_ca);
    std::ostringstream s;
    s << in.rdbuf();
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = s.str();
    return grpc::CreateCustomChannel(o.address, grpc::SslCredentials(ssl), args);
  }
  if (o.insecure)
    return grpc::CreateCustomChannel(o.address, grpc::InsecureChannelCredentials(), args);
  if (loopback(o.address))
    return grpc::CreateCustomChannel(o.address, grpc::experimental::LocalCredentials(LOCAL_TCP),
                                     args);
  throw std::invalid_argument("coordinator " + o.address +
                              " is not on loopback: give --tls-ca, or --insecure to send the "
                              "token in clear text");
}

std::unique_ptr<grpc::ClientContext> make_context(const ChannelOptions& o,
                                                  double deadline_seconds) {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!o.token.empty()) ctx->AddMetadata("authorization", "Bearer " + o.token);
  ctx->set_deadline(std::chrono::system_clock::now() +
                    std::chrono::milliseconds(static_cast<long>(deadline_seconds * 1000)));
  return ctx;
}

std::string read_token_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("--token-file " + path + ": cannot be read");
  std::string token;
  std::getline(in, token);
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  if (token.empty()) throw std::runtime_error("--token-file " + path + ": the first line is empty");
  return token;
}

}  // namespace demcal::rpc
