#pragma once
// Bearer-token auth with two kinds of callers (workers and clients), checked in every handler
// through this one function. The token travels as
// metadata ("authorization: Bearer <token>") added by the client to each call, not as gRPC
// call credentials (Debian's gRPC 1.51 drops call credentials on insecure channels); the
// channel itself is protected by local credentials on loopback or by TLS elsewhere.
#include <grpcpp/grpcpp.h>

#include <string>

namespace demcal::server {

/// Who may call what. `both` opens every service (the operator's token); `worker` only the
/// WorkerService (Lease, Heartbeat, Complete, Fail), `client` only the CampaignService (Submit,
/// Cancel, GiveUp, queries). All empty: auth disabled (only allowed on loopback).
struct Tokens {
  std::string both, worker, client;
  bool empty() const { return both.empty() && worker.empty() && client.empty(); }
};

/// The caller a service admits.
enum class Caller { kWorker, kClient };

/// The one authorization check, called by every handler of both services: OK when the call
/// carries `both` or the token of `caller` (or when auth is disabled); PERMISSION_DENIED for a
/// valid token of the other kind; else UNAUTHENTICATED without saying which part was wrong.
/// Tokens are compared in constant time.
grpc::Status authorize(const grpc::ServerContext& context, const Tokens& tokens, Caller caller);

/// Which token an admitted client call carries: "operator" (`both`), "client", or "" when auth
/// is disabled. What a campaign's owner is recorded as (its unfinished jobs are bounded).
std::string token_name(const grpc::ServerContext& context, const Tokens& tokens);

/// Server credentials for an address: TLS when a certificate is given, local (LOCAL_TCP) on a
/// loopback address, plain TCP only when `insecure` is asked for.
std::shared_ptr<grpc::ServerCredentials> server_credentials(const std::string& address,
                                                            const std::string& tls_cert,
                                                            const std::string& tls_key,
                                                            bool insecure);
bool is_loopback(const std::string& address);

}  // namespace demcal::server
