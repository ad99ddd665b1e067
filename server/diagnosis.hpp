#pragma once
// The coordinator's side of the diagnosis: the stored campaign as a diagnose::Problem, the
// finished diagnosis jobs as its group results, the runs it asks for queued as jobs of kind
// "diagnose:<group>" (row = std_order), and the report as JSON.
#include <string>

#include "core/diagnose/diagnosis.hpp"
#include "demcal/v1/campaign.pb.h"
#include "server/store.hpp"

namespace demcal::server {

/// The diagnosis options of a spec: 0 (proto's unset) takes the default, anything else must be
/// finite and in its range, else InputError naming `where`.<field> (checked at submission too).
diagnose::Options diagnose_options(const v1::DiagnoseOptions& options, const std::string& where);

/// Advances the diagnosis of a campaign: queues the runs it needs that are not stored yet
/// (unless `read_only`) and fills the reply. Throws InputError when the campaign cannot be
/// diagnosed.
v1::DiagnoseReply diagnose_campaign(Store& store, const CampaignRow& row, std::uint64_t seed,
                                    bool read_only = false);

}  // namespace demcal::server
