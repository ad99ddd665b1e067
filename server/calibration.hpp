#pragma once
// The coordinator's side of the sequential calibration (core/calib/sequential.hpp): it builds
// the state from the store (design results, stage designs, verification rounds), asks for the
// next step, and queues its jobs. Verification jobs have kind 'verify' and std_order = round;
// a stage design's jobs have kind 'stage:<n>' and the design rows' std_order.
#include <functional>
#include <string>
#include <vector>

#include "core/calib/sequential.hpp"
#include "demcal/v1/campaign.pb.h"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/store.hpp"

namespace demcal::server {

/// One Calibrate call: the current proposal, every round so far, and the conclusion. With
/// `verify` it advances the loop (queues a round or a stage design) when nothing is running.
/// InputError when there is nothing to calibrate yet (no measurements, design unfinished).
/// `interrupt` is called before every start of every minimisation (calib::CalibrationOptions)
/// and throws calib::Interrupted when nobody waits for the answer any more.
v1::CalibrateReply calibrate_campaign(Store& store, const CampaignRow& row,
                                      const CalibrateCall& call,
                                      std::function<void()> interrupt = {});

/// Particle-steps of a multi-fidelity campaign's finished jobs by level (design and stages at
/// the low level, the design's high rows, the calibration's verifications at the high level),
/// and the design at the high level in every row, from the high jobs' mean.
v1::FidelityCost fidelity_cost(const CampaignPlan& plan, const std::vector<JobRow>& jobs);

/// The stored rounds with their simulated values so far (status and export).
std::vector<v1::CalibrationRound> calibration_rounds(Store& store, const CampaignRow& row);

}  // namespace demcal::server
