#include "rpc/replies.hpp"

#include <google/protobuf/util/json_util.h>

namespace demcal::rpc {

std::string message_json(const google::protobuf::Message& m) {
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.add_whitespace = true;
  o.preserve_proto_field_names = true;
  o.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(m, &out, o);
  return out;
}

grpc::Status read_export(v1::CampaignService::StubInterface& stub, const ChannelOptions& options,
                         std::int64_t id, const std::string& format, std::string& content,
                         bool series, const std::vector<std::int64_t>& jobs) {
  v1::ExportRequest req;
  req.set_id(id);
  req.set_format(format);
  req.set_series(series);
  for (const auto job : jobs) req.add_jobs(job);
  const auto context = make_context(options, 600);
  auto reader = stub.Export(context.get(), req);
  content.clear();
  v1::ExportReply piece;
  while (reader->Read(&piece)) content += piece.content();
  return reader->Finish();
}

}  // namespace demcal::rpc
