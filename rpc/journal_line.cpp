#include "rpc/journal_line.hpp"

#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "rpc/result_check.hpp"

namespace demcal::rpc {
namespace {

void parse_message(const std::string& text, google::protobuf::Message& message) {
  const auto status = google::protobuf::util::JsonStringToMessage(text, &message);
  if (!status.ok()) throw std::invalid_argument(std::string(status.message()));
}

bool is_run_key(const std::string& text) {
  return text.size() == 64 && text.find_first_not_of("0123456789abcdef") == std::string::npos;
}

/// The first key of `values` whose value is not finite; empty when all are.
std::string first_not_finite(const google::protobuf::Map<std::string, double>& values) {
  for (const auto& [name, value] : values)
    if (!std::isfinite(value)) return name;
  return {};
}

}  // namespace

std::string journal_line(const google::protobuf::Message& line) {
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.preserve_proto_field_names = true;
  const auto status = google::protobuf::util::MessageToJsonString(line, &out, o);
  if (!status.ok()) throw std::runtime_error("journal line: " + std::string(status.message()));
  return out;
}

JournalLine parse_journal_line(const std::string& text) {
  // A cut line is no JSON; its error says so before the fields are looked at.
  const auto json = nlohmann::json::parse(text);
  if (!json.is_object()) throw std::invalid_argument("not a JSON object");
  if (json.contains("journal")) {
    v1::JournalHeader header;
    parse_message(text, header);
    if (header.journal() != kJournalMarker)
      throw std::invalid_argument("journal: expected \"" + std::string(kJournalMarker) + "\"");
    if (header.version() != kJournalFormat)
      throw std::invalid_argument("version: " + std::to_string(header.version()) +
                                  " is not this build's journal format " +
                                  std::to_string(kJournalFormat));
    return header;
  }
  v1::JournalRun run;
  parse_message(text, run);
  if (const std::string error = journal_run_error(run); !error.empty())
    throw std::invalid_argument(error);
  return run;
}

std::string journal_run_error(const v1::JournalRun& run) {
  constexpr std::size_t kMaxText = 4096;
  if (!is_run_key(run.run_key())) return "run_key: 64 lower-case hex digits expected";
  for (const auto& [field, text] :
       {std::pair{"test", &run.test()}, {"instance", &run.instance()}, {"source", &run.source()}})
    if (text->size() > kMaxText) return std::string(field) + ": longer than 4096 characters";
  if (run.protocol() < 1) return "protocol: must be >= 1";
  if (run.attempt() < 0) return "attempt: must be >= 0";
  if (const std::string name = first_not_finite(run.settings()); !name.empty())
    return "settings." + name + ": must be finite";
  if (const std::string name = first_not_finite(run.parameters()); !name.empty())
    return "parameters." + name + ": must be finite";
  return result_error(run);
}

}  // namespace demcal::rpc
