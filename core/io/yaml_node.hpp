#pragma once
// A YAML node that knows where it is: the file, the line and the field path. Every read checks
// the type and every map can be checked for unknown keys, so a mistake in a spec is reported as
// "spec.yaml:12: bodies[1].radius: expected a number".
#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/common/vec3.hpp"

namespace demcal::io {

class YamlNode {
 public:
  /// Loads a file; a YAML syntax error becomes an InputError with file and line.
  static YamlNode load_file(const std::string& path);
  static YamlNode load_string(const std::string& text, const std::string& name = "<string>");

  bool has(const std::string& key) const;
  YamlNode operator[](const std::string& key) const;  ///< required child
  std::optional<YamlNode> child(const std::string& key) const;
  std::vector<YamlNode> items() const;    ///< elements of a sequence
  std::vector<std::string> keys() const;  ///< keys of a map
  /// Throws on a key outside `allowed` (a misspelt field must not be silently ignored).
  void expect_only(std::initializer_list<const char*> allowed) const;

  double as_number() const;
  std::string as_string() const;
  bool as_bool() const;
  Vec3 as_vec3() const;
  std::vector<double> as_numbers() const;

  double number(const std::string& key, double fallback) const;
  std::string string(const std::string& key, const std::string& fallback) const;

  const std::string& path() const { return path_; }
  /// The file this node was read from ("<string>" or the given name for a string).
  const std::string& file() const { return file_; }
  /// "file:line: path" for error messages.
  std::string where() const;
  [[noreturn]] void fail(const std::string& what) const;

 private:
  YamlNode(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}
  YamlNode at(const std::string& key) const;
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

}  // namespace demcal::io
