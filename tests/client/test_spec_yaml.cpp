// The campaign spec parser of the CLI (client/spec_yaml.cpp) on text that is not UTF-8, holds a
// control character or has a key that is not a name: an InputError naming the file and line,
// never another exception (each found by fuzz_campaign_yaml; the inputs are kept in
// tests/fuzz/regressions/campaign_yaml).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "client/spec_yaml.hpp"
#include "core/common/error.hpp"

namespace demcal::cli {
namespace {

std::string regression(const std::string& name) {
  std::ifstream in(DEMCAL_SOURCE_DIR "/tests/fuzz/regressions/campaign_yaml/" + name,
                   std::ios::binary);
  std::stringstream found;
  found << in.rdbuf();
  return found.str();
}

/// The message of the InputError parsing `text` throws ("" when it parses or throws another).
std::string input_error(const std::string& text) {
  try {
    parse_campaign_spec(text, "c.yaml");
  } catch (const InputError& e) {
    return e.what();
  } catch (...) {
    return "another exception";
  }
  return "";
}

TEST(SpecYaml, TextThatIsNotUtf8IsAnInputErrorNamingLineAndColumn) {
  const std::string found = regression("invalid-utf8.yaml");
  ASSERT_FALSE(found.empty());
  EXPECT_NE(input_error(found).find("c.yaml:1"), std::string::npos) << input_error(found);
  EXPECT_NE(input_error(found).find("not UTF-8 text: byte 0xFF at column 11"), std::string::npos)
      << input_error(found);
  // Overlong, surrogate, truncated and out-of-range sequences, each on line 2.
  for (const std::string bad : {"\xC0\x80", "\xED\xA0\x80", "\xE2\x82", "\xF4\x90\x80\x80"}) {
    const std::string message = input_error("name: a\ndescription: x" + bad + "\n");
    EXPECT_NE(message.find("c.yaml:2: not UTF-8 text"), std::string::npos) << message;
  }
}

TEST(SpecYaml, AKeyThatIsNotANameIsAnInputErrorNamingItsLine) {
  // examples/lh100_calibration_campaign.yaml with "?" opening a measurement: a complex key.
  const std::string found = regression("complex-key.yaml");
  ASSERT_FALSE(found.empty());
  const std::string message = input_error(found);
  EXPECT_NE(message.find("c.yaml:38"), std::string::npos) << message;
  EXPECT_NE(message.find("a key must be a name"), std::string::npos) << message;
  const std::string list_key = input_error("name: a\n[1, 2]: b\n");
  EXPECT_NE(list_key.find("c.yaml:2: the spec: a key must be a name"), std::string::npos)
      << list_key;
  const std::string map_key = input_error("material:\n  {x: 1}: 2\n");
  EXPECT_NE(map_key.find("c.yaml:2: material: a key must be a name"), std::string::npos) << map_key;
}

TEST(SpecYaml, AControlCharacterOrALoneSurrogateIsAnInputError) {
  // examples/lh100_calibration_campaign.yaml with a NUL byte in a key (fuzz_campaign_yaml): not
  // printable YAML; yaml-cpp read past it.
  const std::string found = regression("nul-in-key.yaml");
  ASSERT_FALSE(found.empty());
  const std::string message = input_error(found);
  EXPECT_NE(message.find("c.yaml:27: a control character, byte 0x00 at column 8"),
            std::string::npos)
      << message;
  // An escape of a lone surrogate (it would decode to bytes that are not UTF-8): yaml-cpp
  // refuses it, and the error names the line.
  const std::string value = input_error("name: a\ndescription: \"x\\uD800\"\n");
  EXPECT_NE(value.find("c.yaml:2: invalid unicode"), std::string::npos) << value;
}

TEST(SpecYaml, EscapesYamlCppDecodesToSingleBytesAreAnInputError) {
  // A double-quoted string over several lines with "\_" in it (fuzz_campaign_yaml): yaml-cpp
  // decodes the escape to the byte 0xA0 instead of U+00A0's two bytes.
  const std::string found = regression("nbsp-escape.yaml");
  ASSERT_FALSE(found.empty());
  const std::string message = input_error(found);
  EXPECT_NE(message.find("c.yaml:2: factors[0].source: an escape decodes to text that is not"),
            std::string::npos)
      << message;
  for (const std::string escape : {"\\_", "\\N"}) {
    const std::string value = input_error("name: a\ndescription: \"x" + escape + "\"\n");
    EXPECT_NE(value.find("c.yaml:2: description: an escape decodes"), std::string::npos) << value;
  }
  // The same characters written as \u escapes are text.
  EXPECT_EQ(input_error("name: a\ndescription: \"x\\u00A0\\u0085\"\n").find("escape"),
            std::string::npos);
}

TEST(SpecYaml, Utf8BeyondAsciiIsText) {
  // U+00B5 and U+2013 (two and three bytes) in a name: no UTF-8 complaint.
  const std::string message = input_error("name: \"\xC2\xB5m \xE2\x80\x93 test\"\n");
  EXPECT_EQ(message.find("UTF-8"), std::string::npos) << message;
}

}  // namespace
}  // namespace demcal::cli
