// Fuzzes the CLI's campaign spec parser (cli::parse_campaign_spec: YAML -> JSON -> protobuf's
// JSON parser, with the line of every field kept for messages) with arbitrary text: it must
// return a CampaignSpec or throw InputError, and a message of the coordinator about any field it
// returned must be locatable (SpecFile::locate walks the recorded paths).
#include <cstddef>
#include <cstdint>
#include <string>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto file = demcal::cli::parse_campaign_spec(text, "fuzz.yaml");
    for (const auto& [path, line] : file.lines) (void)file.locate("spec." + path + ": fuzz");
  } catch (const demcal::InputError&) {
  }
  return 0;
}
