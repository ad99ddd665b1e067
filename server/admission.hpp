#pragma once
// Checks of what a request carries, before anything else reads it (limits.hpp): its bytes, every
// repeated field and string of a spec and its unknown fields, a worker's texts. Errors name the
// field.
#include <google/protobuf/message.h>

#include <string>

namespace demcal::server {

/// Throws InputError naming the field when a string or a map key of `message` is longer than
/// kMaxText bytes, a repeated field or map has more than kMaxRepeated entries, or a message holds
/// a field this build does not know (a newer client's: refused, not silently dropped from what
/// is stored and run); `where` is the path of `message` itself ("spec").
void check_fields(const google::protobuf::Message& message, const std::string& where);

/// `text` as an error message repeats it: at most kMaxEcho characters, the rest cut ("...").
std::string echo(const std::string& text);

/// Throws InputError naming `where` when `text` holds a control character (C0, DEL or C1: a
/// terminal escape printed by `demcal list`).
void check_printable(const std::string& text, const std::string& where);

/// "" when `bytes` is at most `max`, else "request: N bytes, at most M (METHOD)".
std::string request_size_error(std::size_t bytes, std::size_t max, const std::string& method);

}  // namespace demcal::server
