#include "server/admission.hpp"

#include <fmt/format.h>

#include <vector>

#include "core/common/error.hpp"
#include "server/limits.hpp"

namespace demcal::server {
namespace {

using google::protobuf::FieldDescriptor;

void check_text(const std::string& text, const std::string& where, const char* what) {
  if (text.size() > kMaxText)
    throw InputError(where, fmt::format("{} of {} bytes, at most {}", what, text.size(), kMaxText));
}

/// The key of a map entry (its field 1), checked, and its value if it is a message.
void check_map_entry(const google::protobuf::Message& entry, const std::string& where) {
  const auto* r = entry.GetReflection();
  const auto* d = entry.GetDescriptor();
  const FieldDescriptor* key = d->map_key();
  const FieldDescriptor* value = d->map_value();
  std::string name;
  if (key->cpp_type() == FieldDescriptor::CPPTYPE_STRING) {
    name = r->GetString(entry, key);
    check_text(name, where, "a key");
  }
  if (value->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE)
    check_fields(r->GetMessage(entry, value), where + "." + name);
  else if (value->cpp_type() == FieldDescriptor::CPPTYPE_STRING)
    check_text(r->GetString(entry, value), where + "." + name, "a text");
}

void check_repeated(const google::protobuf::Message& m, const FieldDescriptor* f,
                    const std::string& where) {
  const auto* r = m.GetReflection();
  const int n = r->FieldSize(m, f);
  if (n > kMaxRepeated)
    throw InputError(where, fmt::format("{} entries, at most {}", n, kMaxRepeated));
  for (int i = 0; i < n; ++i) {
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (f->is_map())
      check_map_entry(r->GetRepeatedMessage(m, f, i), where);
    else if (f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE)
      check_fields(r->GetRepeatedMessage(m, f, i), at);
    else if (f->cpp_type() == FieldDescriptor::CPPTYPE_STRING)
      check_text(r->GetRepeatedString(m, f, i), at, "a text");
  }
}

}  // namespace

void check_fields(const google::protobuf::Message& message, const std::string& where) {
  const auto* r = message.GetReflection();
  if (const auto& unknown = r->GetUnknownFields(message); unknown.field_count() > 0)
    throw InputError(where,
                     fmt::format("field number {} is not one this coordinator knows (sent by "
                                 "a newer client?): refused rather than ignored",
                                 unknown.field(0).number()));
  std::vector<const FieldDescriptor*> fields;
  r->ListFields(message, &fields);
  for (const FieldDescriptor* f : fields) {
    const std::string at = where + "." + f->name();
    if (f->is_repeated())
      check_repeated(message, f, at);
    else if (f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE)
      check_fields(r->GetMessage(message, f), at);
    else if (f->cpp_type() == FieldDescriptor::CPPTYPE_STRING)
      check_text(r->GetString(message, f), at, "a text");
  }
}

std::string echo(const std::string& text) {
  if (text.size() <= kMaxEcho) return text;
  std::size_t cut = kMaxEcho;
  // Not inside a UTF-8 sequence: back to the start of the character.
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return text.substr(0, cut) + "...";
}

void check_printable(const std::string& text, const std::string& where) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    const bool c0_or_del = c < 0x20 || c == 0x7F;
    // U+0080..U+009F are C2 80..C2 9F in UTF-8.
    const bool c1 = c == 0xC2 && i + 1 < text.size() &&
                    static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                    static_cast<unsigned char>(text[i + 1]) <= 0x9F;
    if (c0_or_del || c1)
      throw InputError(where, fmt::format("a control character at byte {} (a name is printed as "
                                          "it is: no escapes, line breaks or tabs)",
                                          i));
  }
}

std::string request_size_error(std::size_t bytes, std::size_t max, const std::string& method) {
  if (bytes <= max) return {};
  return fmt::format("request: {} bytes, at most {} for {}", bytes, max, method);
}

}  // namespace demcal::server
