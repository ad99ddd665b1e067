#pragma once
// Campaign specs in YAML: YAML -> JSON -> protobuf's JSON parser, so an unknown field or a bad
// value is an error with its path, reported as "campaign.yaml:12: factors[0].scale: ...".
// Contact-law slots are written as in `demcal lab run` (parameters next to `model`); they are
// moved under `params` on the way, so users see one schema.
#include <map>
#include <string>

#include "demcal/v1/campaign.pb.h"

namespace demcal::cli {

struct SpecFile {
  v1::CampaignSpec spec;
  std::string name;
  std::map<std::string, int> lines;  ///< field path (proto and user spelling) -> line
  /// The coordinator's "spec.factors[0].high: ..." as "file:line: factors[0].high: ...".
  std::string locate(const std::string& server_message) const;
};

/// Reads and parses a spec file; InputError "file:line: path: what" on any mistake.
SpecFile read_campaign_spec(const std::string& path);
/// Same from text (`name` stands for the file in messages).
SpecFile parse_campaign_spec(const std::string& yaml, const std::string& name);

}  // namespace demcal::cli
