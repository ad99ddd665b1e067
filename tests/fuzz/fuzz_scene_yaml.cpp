// Fuzzes the YAML reader and the scene parser (io::YamlNode::load_string, io::read_scene: the
// parameter tables, ranges and field paths every spec goes through) with arbitrary text: it must
// return a scene or throw InputError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/common/error.hpp"
#include "core/io/scene_yaml.hpp"
#include "core/io/yaml_node.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto scene = demcal::io::read_scene(demcal::io::YamlNode::load_string(text, "fuzz"));
    (void)scene;
  } catch (const demcal::InputError&) {
  }
  return 0;
}
