#pragma once
// A campaign's journal on the coordinator's side (docs/journal.md; the line format is
// rpc/journal_line.hpp): Export writes the campaign's finished jobs as journal lines, ImportRuns
// keeps the runs of a journal for the jobs with their run keys (Store::lease takes them).
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "demcal/v1/campaign.pb.h"
#include "server/store.hpp"

namespace demcal::server {

/// The journal of a campaign: its header, then one line per finished job with a run key, of
/// the jobs in `only` when it is not empty, in job order. `series`: job id -> stored curves.
std::string export_journal(const CampaignRow& row, const std::vector<JobRow>& jobs,
                           const std::map<std::int64_t, std::string>& series,
                           const std::set<std::int64_t>& only);

/// What an ImportRuns call did with its runs.
struct ImportCounts {
  int kept = 0, known = 0, other_protocol = 0;
};

/// Keeps the runs offered for later jobs with their run keys; those simulated under another lab
/// protocol version are counted, not kept. InputError naming the run (its source, FILE:LINE,
/// or runs[i]) and the field when a run is not valid; nothing is kept then.
ImportCounts import_runs(Store& store, const v1::ImportRunsRequest& request);

}  // namespace demcal::server
