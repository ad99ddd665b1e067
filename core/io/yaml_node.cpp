#include "core/io/yaml_node.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"

namespace demcal::io {

YamlNode YamlNode::load_file(const std::string& path) {
  try {
    return YamlNode(YAML::LoadFile(path), path, "");
  } catch (const YAML::BadFile&) {
    throw InputError(path, "cannot open file");
  } catch (const YAML::ParserException& e) {
    throw InputError(path + ":" + std::to_string(e.mark.line + 1), "YAML syntax error: " + e.msg);
  }
}

YamlNode YamlNode::load_string(const std::string& text, const std::string& name) {
  try {
    return YamlNode(YAML::Load(text), name, "");
  } catch (const YAML::ParserException& e) {
    throw InputError(name + ":" + std::to_string(e.mark.line + 1), "YAML syntax error: " + e.msg);
  }
}

std::string YamlNode::where() const {
  std::string w = file_;
  if (node_.IsDefined() && node_.Mark().line >= 0) w += ":" + std::to_string(node_.Mark().line + 1);
  if (!path_.empty()) w += ": " + path_;
  return w;
}

void YamlNode::fail(const std::string& what) const {
  throw InputError(where(), what);
}

bool YamlNode::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined();
}

YamlNode YamlNode::at(const std::string& key) const {
  return YamlNode(node_[key], file_, path_.empty() ? key : path_ + "." + key);
}

YamlNode YamlNode::operator[](const std::string& key) const {
  if (!node_.IsMap()) fail("expected a map with the field '" + key + "'");
  if (!node_[key].IsDefined()) fail("missing required field '" + key + "'");
  return at(key);
}

std::optional<YamlNode> YamlNode::child(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return at(key);
}

std::vector<YamlNode> YamlNode::items() const {
  if (!node_.IsSequence()) fail("expected a list");
  std::vector<YamlNode> out;
  for (std::size_t k = 0; k < node_.size(); ++k)
    out.push_back(YamlNode(node_[k], file_, path_ + "[" + std::to_string(k) + "]"));
  return out;
}

std::vector<std::string> YamlNode::keys() const {
  if (!node_.IsMap()) fail("expected a map");
  std::vector<std::string> out;
  for (const auto& kv : node_) {
    // A key that is itself a list or a map ("{[a, b]: 1}") names no field.
    if (!kv.first.IsScalar()) fail("a key must be a name, not a list or a map");
    out.push_back(kv.first.Scalar());
  }
  return out;
}

void YamlNode::expect_only(std::initializer_list<const char*> allowed) const {
  for (const auto& key : keys())
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      at(key).fail("unknown field (allowed here: " + list + ")");
    }
}

double YamlNode::as_number() const {
  if (!node_.IsScalar()) fail("expected a number");
  try {
    const double v = node_.as<double>();
    if (!std::isfinite(v)) fail("expected a finite number");
    return v;
  } catch (const YAML::Exception&) {
    fail("expected a number, got '" + node_.Scalar() + "'");
  }
}

std::string YamlNode::as_string() const {
  if (!node_.IsScalar()) fail("expected a string");
  return node_.Scalar();
}

bool YamlNode::as_bool() const {
  if (!node_.IsScalar()) fail("expected true or false");
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false, got '" + node_.Scalar() + "'");
  }
}

std::vector<double> YamlNode::as_numbers() const {
  std::vector<double> out;
  for (const auto& item : items()) out.push_back(item.as_number());
  return out;
}

Vec3 YamlNode::as_vec3() const {
  const auto v = as_numbers();
  if (v.size() != 3) fail("expected a list of 3 numbers");
  return {v[0], v[1], v[2]};
}

double YamlNode::number(const std::string& key, double fallback) const {
  return has(key) ? at(key).as_number() : fallback;
}

std::string YamlNode::string(const std::string& key, const std::string& fallback) const {
  return has(key) ? at(key).as_string() : fallback;
}

}  // namespace demcal::io
