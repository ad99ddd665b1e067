#pragma once
// The coordinator's side of the diagnosis: the stored plan as a diagnose::Problem, the finished
// diagnosis jobs as its group results, the runs it asks for queued as jobs of kind
// job_kind::diagnosis(group) (row = std_order), and the report as its reply.
#include <string>

#include "core/diagnose/diagnosis.hpp"
#include "demcal/v1/campaign.pb.h"
#include "server/plan.hpp"
#include "server/store.hpp"

namespace demcal::server {

/// The stored plan as the diagnosis's problem: its factors, design, the results of `jobs`, the
/// measurements, and what its material and test instances make of each candidate (the
/// `preparation` candidate: poured cohesive beds and at least one instance that can build its bed
/// from clusters and has no preparation of its own; the others pour in its runs).
diagnose::Problem make_problem(const CampaignPlan& plan, const std::vector<JobRow>& jobs,
                               std::uint64_t seed);

/// Sets the number of verification rounds of campaign `row`'s diagnosis (`rounds`, in the range
/// of the spec's diagnose.rounds) in its stored spec and plan, when it differs from theirs, and
/// returns the row as stored then. Its jobs and results are kept: the diagnosis goes on from them,
/// queuing the rounds it adds or none more. InputError at "rounds" for a value out of range.
CampaignRow with_diagnosis_rounds(Store& store, const CampaignRow& row, int rounds);

/// Advances the diagnosis of a campaign: queues the runs it needs that are not stored yet
/// (unless `read_only`) and fills the reply. Throws InputError when the campaign cannot be
/// diagnosed.
v1::DiagnoseReply diagnose_campaign(Store& store, const CampaignRow& row, std::uint64_t seed,
                                    bool read_only = false);

}  // namespace demcal::server
