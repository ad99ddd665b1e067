#pragma once
// Client side of the transport, shared by the worker and the CLI: the channel to a
// coordinator and the bearer token on each call. The token is added as call metadata, not as
// call credentials (Debian's gRPC 1.51 drops those on channels it considers insecure); the
// channel uses local credentials on loopback, TLS when a CA file is given.
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

namespace demcal::rpc {

struct ChannelOptions {
  std::string address;  ///< host:port
  std::string token;
  std::string tls_ca;     ///< PEM file of the CA that signed the coordinator's certificate
  bool insecure = false;  ///< plain TCP (a coordinator started with --insecure)
};

/// The largest checkpoint a coordinator may be configured to take (--max-checkpoint-mb).
constexpr double kMaxCheckpointMb = 1024.0;
/// The message size that holds a checkpoint of `max_checkpoint_mb` MiB with its call's other
/// fields: a coordinator's receive limit, and a channel's (a lease hands the checkpoint back).
int checkpoint_message_limit(double max_checkpoint_mb);

/// A channel that receives messages up to checkpoint_message_limit(kMaxCheckpointMb).
std::shared_ptr<grpc::Channel> make_channel(const ChannelOptions& options);

/// The bearer token in the first line of `path` (trailing blanks dropped). Throws
/// std::runtime_error naming the file when it cannot be read or its first line is empty: a
/// token file that was asked for and is missing never means "no token" (fail closed).
std::string read_token_file(const std::string& path);

/// A context carrying the token and a deadline.
std::unique_ptr<grpc::ClientContext> make_context(const ChannelOptions& options,
                                                  double deadline_seconds);

}  // namespace demcal::rpc
