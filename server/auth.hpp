#pragma once
// Bearer-token auth, checked in every handler through this one helper. The token travels as
// metadata ("authorization: Bearer <token>") added by the client to each call, not as gRPC
// call credentials (Debian's gRPC 1.51 drops call credentials on insecure channels); the
// channel itself is protected by local credentials on loopback or by TLS elsewhere.
#include <grpcpp/grpcpp.h>

#include <string>

namespace demcal::server {

/// OK when the call carries the token (or when `token` is empty: auth disabled), else
/// UNAUTHENTICATED without saying which part was wrong.
grpc::Status authorize(const grpc::ServerContext& context, const std::string& token);

/// Server credentials for an address: TLS when a certificate is given, local (LOCAL_TCP) on a
/// loopback address, plain TCP only when `insecure` is asked for.
std::shared_ptr<grpc::ServerCredentials> server_credentials(const std::string& address,
                                                            const std::string& tls_cert,
                                                            const std::string& tls_key,
                                                            bool insecure);
bool is_loopback(const std::string& address);

}  // namespace demcal::server
