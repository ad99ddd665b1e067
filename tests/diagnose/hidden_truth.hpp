#pragma once
// What the hidden-effect system tests share: a number as their YAML writes it, a demcal command
// whose standard output is JSON, a fresh directory for a truth and its campaign, and the
// diagnosis of that campaign as a user runs it. DEMCAL_CLI_BIN is the demcal binary.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/common/command.hpp"

namespace demcal::test {

/// The seed a test draws its hidden truth from: its first argument (after gtest's), else
/// DEMCAL_HIDDEN_SEED, else 1.
inline std::uint64_t hidden_seed(int argc, char** argv) {
  if (argc > 1) return std::stoull(argv[1]);
  if (const char* s = std::getenv("DEMCAL_HIDDEN_SEED")) return std::stoull(s);
  return 1;
}

/// A number for a spec or lab-run YAML, in ten significant digits.
inline std::string num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

/// Runs a demcal command (it must succeed) and parses its standard output as JSON.
inline nlohmann::json run_json(const std::string& cmd) {
  const CommandResult r = run_command(cmd);
  EXPECT_EQ(r.exit_code, 0) << cmd;
  return nlohmann::json::parse(r.out);
}

/// An empty directory under the temporary one for test `name` at seed `seed`.
inline std::filesystem::path fresh_directory(const std::string& name, std::uint64_t seed) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("demcal-hidden-" + name + "-" + std::to_string(seed) + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// `demcal diagnose DIR/campaign.yaml` on the embedded default with two workers of one thread
/// (work directory DIR/work, its log DIR/diagnose.log): the report as JSON.
inline nlohmann::json diagnose_json(const std::filesystem::path& dir) {
  return run_json(std::string(DEMCAL_CLI_BIN) + " diagnose " + (dir / "campaign.yaml").string() +
                  " --format json --workers 2 --threads 1 --workdir " + (dir / "work").string() +
                  " 2>" + (dir / "diagnose.log").string());
}

/// The candidate `id` of a report; null when it was not tested.
inline nlohmann::json candidate(const nlohmann::json& report, const std::string& id) {
  for (const auto& c : report["candidates"])
    if (c["id"] == id) return c;
  return nullptr;
}

}  // namespace demcal::test
