#pragma once
// gRPC server reflection (grpc.reflection.v1alpha, the protocol grpcurl and grpc_cli speak),
// served from the descriptors compiled into this process, behind the token check of the
// campaign service: reflection names every service, method and message, so only a caller who
// may use the campaign service may read it. gRPC's own reflection plugin cannot be put behind a
// check (a registered plugin is served to anyone who connects, and gRPC 1.51's server
// interceptors cannot refuse a call), hence this service of our own.
#include <string>
#include <vector>

#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "server/auth.hpp"

namespace demcal::server {

class ReflectionService final : public grpc::reflection::v1alpha::ServerReflection::Service {
 public:
  /// `services`: the full names of the services the server registers (listed as they are).
  ReflectionService(Tokens tokens, std::vector<std::string> services);

  grpc::Status ServerReflectionInfo(
      grpc::ServerContext* ctx,
      grpc::ServerReaderWriter<grpc::reflection::v1alpha::ServerReflectionResponse,
                               grpc::reflection::v1alpha::ServerReflectionRequest>* stream)
      override;

 private:
  /// The answer to one request of the stream (an error_response when it names nothing known).
  grpc::reflection::v1alpha::ServerReflectionResponse answer(
      const grpc::reflection::v1alpha::ServerReflectionRequest& request) const;
  Tokens tokens_;
  std::vector<std::string> services_;
};

}  // namespace demcal::server
