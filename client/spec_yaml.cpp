#include "client/spec_yaml.hpp"

#include <google/protobuf/util/json_util.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/common/error.hpp"
#include "core/io/contact_law_yaml.hpp"
#include "core/io/material_yaml.hpp"
#include "rpc/material_convert.hpp"
#include "rpc/replies.hpp"

namespace demcal::cli {
namespace {

using Json = nlohmann::ordered_json;

/// The length of the well-formed UTF-8 sequence at text[at] (RFC 3629 section 4: no overlong
/// forms, no surrogates, nothing above U+10FFFF), or 0 when it is not one.
std::size_t utf8_sequence(const std::string& text, std::size_t at) {
  const auto byte = [&](std::size_t i) {
    return i < text.size() ? static_cast<unsigned char>(text[i]) : 0u;
  };
  const unsigned b0 = byte(at);
  const auto tail = [&](std::size_t i, unsigned lo = 0x80, unsigned hi = 0xBF) {
    return byte(at + i) >= lo && byte(at + i) <= hi;
  };
  if (b0 < 0x80) return 1;
  if (b0 >= 0xC2 && b0 <= 0xDF) return tail(1) ? 2 : 0;
  if (b0 >= 0xE0 && b0 <= 0xEF) {
    const unsigned lo = b0 == 0xE0 ? 0xA0 : 0x80, hi = b0 == 0xED ? 0x9F : 0xBF;
    return tail(1, lo, hi) && tail(2) ? 3 : 0;
  }
  if (b0 >= 0xF0 && b0 <= 0xF4) {
    const unsigned lo = b0 == 0xF0 ? 0x90 : 0x80, hi = b0 == 0xF4 ? 0x8F : 0xBF;
    return tail(1, lo, hi) && tail(2) && tail(3) ? 4 : 0;
  }
  return 0;
}

/// InputError "name:line: ..." at the first byte of `text` that is not UTF-8 or is a control
/// character YAML does not allow. A spec is UTF-8 text (its strings become protobuf strings,
/// which must be UTF-8); yaml-cpp passes other bytes through (and reads past a NUL), and the
/// JSON writer on the way to protobuf would stop at them with an exception of its own.
void require_utf8(const std::string& text, const std::string& name) {
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t n = utf8_sequence(text, at);
    const auto c = static_cast<unsigned char>(text[at]);
    // YAML 1.2 §5.1: a stream is printable: no C0 control but tab, LF and CR, no DEL.
    const bool control = (c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7F;
    if (n == 0 || control) {
      char byte[8];
      std::snprintf(byte, sizeof byte, "0x%02X", c);
      throw InputError(
          name + ":" + std::to_string(line),
          std::string(control ? "a control character, byte " : "not UTF-8 text: byte ") + byte +
              " at column " + std::to_string(at - line_start + 1));
    }
    if (text[at] == '\n') {
      ++line;
      line_start = at + 1;
    }
    at += n;
  }
}

struct Place {
  std::string path;  ///< as the user wrote it
  int line = 0;
};

class Converter {
 public:
  explicit Converter(std::string file) : file_(std::move(file)) {}
  std::map<std::string, Place> places;  ///< proto JSON path -> user path and line

  Json convert(const YAML::Node& n, const std::string& path, const std::string& user_path) {
    places[path] = {user_path, n.Mark().line + 1};
    switch (n.Type()) {
      case YAML::NodeType::Map: {
        Json j = Json::object();
        for (const auto& kv : n) {
          if (!kv.first.IsScalar())
            throw InputError(file_ + ":" + std::to_string(kv.first.Mark().line + 1),
                             (user_path.empty() ? std::string("the spec") : user_path) +
                                 ": a key must be a name, not a list, a map or empty");
          const std::string key = decoded(kv.first, user_path);
          const std::string child = path.empty() ? key : path + "." + key;
          const std::string user_child = user_path.empty() ? key : user_path + "." + key;
          j[key] = convert(kv.second, child, user_child);
        }
        return j;
      }
      case YAML::NodeType::Sequence: {
        Json j = Json::array();
        for (std::size_t i = 0; i < n.size(); ++i) {
          const std::string s = "[" + std::to_string(i) + "]";
          j.push_back(convert(n[i], path + s, user_path + s));
        }
        return j;
      }
      case YAML::NodeType::Scalar: {
        const std::string s = decoded(n, user_path);
        if (n.Tag() == "!") return s;  // quoted: a string
        if (s == "true" || s == "false") return s == "true";
        try {
          std::size_t used = 0;
          const double v = std::stod(s, &used);
          if (used == s.size()) {
            // JSON has no NaN or infinity (they would be written as null, i.e. the default):
            // refuse them here, with their line.
            if (!std::isfinite(v))
              throw InputError(file_ + ":" + std::to_string(n.Mark().line + 1) + ": " + user_path,
                               "'" + s + "' is not a finite number");
            if (s.find_first_of(".eE") == std::string::npos && std::abs(v) < 9e15)
              return static_cast<std::int64_t>(v);
            return v;
          }
        } catch (const std::invalid_argument&) {
        } catch (const std::out_of_range&) {
        }
        return s;
      }
      default:
        return nullptr;
    }
  }

 private:
  /// A scalar's text as yaml-cpp decodes it, refused with its line when it is not UTF-8: the
  /// YAML escapes "\_" (U+00A0) and "\N" (U+0085) of a double-quoted string come out of
  /// yaml-cpp 0.7 as one byte each, not as their UTF-8 encoding.
  std::string decoded(const YAML::Node& n, const std::string& user_path) const {
    const std::string& s = n.Scalar();
    for (std::size_t at = 0; at < s.size();) {
      const std::size_t len = utf8_sequence(s, at);
      if (len == 0)
        throw InputError(file_ + ":" + std::to_string(n.Mark().line + 1),
                         (user_path.empty() ? std::string("the spec") : user_path) +
                             ": an escape decodes to text that is not UTF-8 (write \\u00A0 for "
                             "\\_ and \\u0085 for \\N)");
      at += len;
    }
    return s;
  }
  std::string file_;
};

/// "(factors[0]) sclae: Cannot find field." or "(factors[0].low): invalid value ..."
std::pair<std::string, std::string> split_status(const std::string& text) {
  if (text.size() > 1 && text[0] == '(') {
    const auto close = text.find(')');
    if (close != std::string::npos) {
      std::string path = text.substr(1, close - 1);
      std::string rest = text.substr(close + 1);
      if (rest.rfind(": ", 0) == 0) return {path, rest.substr(2)};
      if (!rest.empty() && rest[0] == ' ') {
        const auto colon = rest.find(": ");
        if (colon != std::string::npos) {
          const std::string field = rest.substr(1, colon - 1);
          return {path.empty() ? field : path + "." + field, rest.substr(colon + 2)};
        }
      }
    }
  }
  return {"", text};
}

/// The material and each test's own wall law and preparation as the material's one reader reads
/// them (core/io/material_yaml.hpp: errors with file, line and field), in their proto form: the
/// generic conversion of those blocks is replaced.
void read_material_blocks(const std::string& yaml, const std::string& name, Json& json) {
  const io::YamlNode root = io::YamlNode::load_string(yaml, name);
  if (const auto m = root.child("material"))
    json["material"] =
        Json::parse(rpc::message_json(rpc::to_material_message(io::read_material(*m))));
  const auto tests = root.child("tests");
  if (!tests) return;
  const auto items = tests->items();
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (const auto law = items[i].child("wall_law"))
      json["tests"][i]["wall_law"] =
          Json::parse(rpc::message_json(rpc::to_law_message(io::read_contact_law_spec(*law))));
    if (const auto prep = items[i].child("preparation"))
      json["tests"][i]["preparation"] =
          Json::parse(rpc::message_json(rpc::to_preparation_message(io::read_preparation(*prep))));
  }
}

}  // namespace

std::string SpecFile::locate(const std::string& message) const {
  if (message.rfind("spec.", 0) != 0) return message;
  const auto colon = message.find(": ");
  if (colon == std::string::npos) return message;
  std::string probe = message.substr(5, colon - 5);
  // "material.particle_law.normal.params.k1" is written "material.particle_law.normal.k1".
  const auto params = probe.find(".params.");
  if (params != std::string::npos) probe.erase(params, 7);
  while (!probe.empty() && !lines.count(probe)) {
    const auto cut = probe.find_last_of(".[");
    probe = cut == std::string::npos ? "" : probe.substr(0, cut);
  }
  const int line = probe.empty() ? 0 : lines.at(probe);
  return name + (line ? ":" + std::to_string(line) : "") + ": " + message.substr(5);
}

SpecFile parse_campaign_spec(const std::string& yaml, const std::string& name) {
  require_utf8(yaml, name);
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw InputError(name + ":" + std::to_string(e.mark.line + 1), e.msg);
  }
  if (!root.IsMap()) throw InputError(name, "a campaign spec is a map (name, material, ...)");
  Converter c(name);
  Json json = c.convert(root, "", "");
  read_material_blocks(yaml, name, json);
  SpecFile file;
  file.name = name;
  for (const auto& [proto_path, place] : c.places) {
    file.lines[proto_path] = place.line;
    file.lines[place.path] = place.line;
  }
  v1::CampaignSpec& spec = file.spec;
  google::protobuf::util::JsonParseOptions o;
  o.case_insensitive_enum_parsing = true;  // `scale: log`, `type: fractional_factorial`
  const auto status = google::protobuf::util::JsonStringToMessage(json.dump(), &spec, o);
  if (!status.ok()) {
    auto [path, what] = split_status(std::string(status.message()));
    // The deepest known place at or above the path gives the line.
    std::string probe = path;
    while (!probe.empty() && !c.places.count(probe)) {
      const auto cut = probe.find_last_of(".[");
      probe = cut == std::string::npos ? "" : probe.substr(0, cut);
    }
    const Place place = c.places.count(probe) ? c.places[probe] : Place{"", 1};
    std::string user = place.path;
    if (probe != path) user += path.substr(probe.size());
    throw InputError(name + ":" + std::to_string(place.line) + ": " + (user.empty() ? path : user),
                     what);
  }
  return file;
}

SpecFile read_campaign_spec(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_campaign_spec(s.str(), path);
}

}  // namespace demcal::cli
