#include "server/reflection.hpp"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/descriptor.pb.h>
#include <spdlog/spdlog.h>

#include <set>

namespace demcal::server {

namespace refl = grpc::reflection::v1alpha;
namespace pb = google::protobuf;

namespace {

/// Adds `file` and, depth first, every file it imports (each once) to `out`, serialised as
/// FileDescriptorProto: a client needs the imports to resolve the types `file` refers to.
void add_file_with_imports(const pb::FileDescriptor* file, refl::FileDescriptorResponse& out,
                           std::set<std::string>& added) {
  if (!added.insert(file->name()).second) return;
  pb::FileDescriptorProto proto;
  file->CopyTo(&proto);
  out.add_file_descriptor_proto(proto.SerializeAsString());
  for (int i = 0; i < file->dependency_count(); ++i)
    add_file_with_imports(file->dependency(i), out, added);
}

refl::ServerReflectionResponse error_response(grpc::StatusCode code, const std::string& message) {
  refl::ServerReflectionResponse response;
  response.mutable_error_response()->set_error_code(code);
  response.mutable_error_response()->set_error_message(message);
  return response;
}

refl::ServerReflectionResponse not_found(const std::string& what) {
  return error_response(grpc::StatusCode::NOT_FOUND, what + " is not known to this server");
}

/// A file descriptor response for `file`, or NOT_FOUND naming `what` when it is null.
refl::ServerReflectionResponse file_response(const pb::FileDescriptor* file,
                                             const std::string& what) {
  if (!file) return not_found(what);
  refl::ServerReflectionResponse response;
  std::set<std::string> added;
  add_file_with_imports(file, *response.mutable_file_descriptor_response(), added);
  return response;
}

}  // namespace

ReflectionService::ReflectionService(Tokens tokens, std::vector<std::string> services)
    : tokens_(std::move(tokens)), services_(std::move(services)) {}

grpc::Status ReflectionService::ServerReflectionInfo(
    grpc::ServerContext* ctx,
    grpc::ServerReaderWriter<refl::ServerReflectionResponse, refl::ServerReflectionRequest>*
        stream) {
  if (auto s = authorize(*ctx, tokens_, Caller::kClient); !s.ok()) {
    spdlog::warn("reflection call from {}: {}", ctx->peer(), s.error_message());
    return s;
  }
  refl::ServerReflectionRequest request;
  while (stream->Read(&request)) {
    auto response = answer(request);
    response.set_valid_host(request.host());
    *response.mutable_original_request() = request;
    if (!stream->Write(response)) break;
  }
  return grpc::Status::OK;
}

refl::ServerReflectionResponse ReflectionService::answer(
    const refl::ServerReflectionRequest& request) const {
  const pb::DescriptorPool& pool = *pb::DescriptorPool::generated_pool();
  using Case = refl::ServerReflectionRequest::MessageRequestCase;
  switch (request.message_request_case()) {
    case Case::kListServices: {
      refl::ServerReflectionResponse response;
      for (const auto& name : services_)
        response.mutable_list_services_response()->add_service()->set_name(name);
      return response;
    }
    case Case::kFileByFilename:
      return file_response(pool.FindFileByName(request.file_by_filename()),
                           "file " + request.file_by_filename());
    case Case::kFileContainingSymbol:
      return file_response(pool.FindFileContainingSymbol(request.file_containing_symbol()),
                           "symbol " + request.file_containing_symbol());
    case Case::kFileContainingExtension: {
      const auto& ext = request.file_containing_extension();
      const pb::Descriptor* type = pool.FindMessageTypeByName(ext.containing_type());
      if (!type) return not_found("type " + ext.containing_type());
      const pb::FieldDescriptor* field = pool.FindExtensionByNumber(type, ext.extension_number());
      return file_response(
          field ? field->file() : nullptr,
          "extension " + std::to_string(ext.extension_number()) + " of " + ext.containing_type());
    }
    case Case::kAllExtensionNumbersOfType: {
      const std::string& name = request.all_extension_numbers_of_type();
      const pb::Descriptor* type = pool.FindMessageTypeByName(name);
      if (!type) return not_found("type " + name);
      std::vector<const pb::FieldDescriptor*> extensions;
      pool.FindAllExtensions(type, &extensions);
      refl::ServerReflectionResponse response;
      auto& numbers = *response.mutable_all_extension_numbers_response();
      numbers.set_base_type_name(name);
      for (const auto* e : extensions) numbers.add_extension_number(e->number());
      return response;
    }
    case Case::MESSAGE_REQUEST_NOT_SET:
      break;
  }
  return error_response(grpc::StatusCode::INVALID_ARGUMENT, "the request asks for nothing");
}

}  // namespace demcal::server
