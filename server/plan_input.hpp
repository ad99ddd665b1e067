#pragma once
// The spec read into the plan's structure: the material, fixed values, instances (their settings
// as given), factors and ties, seed policy, and the calibration and diagnosis options. The one
// place the campaign's spec fields are read (plan_campaign validates what they say against the
// catalogue and the material; a campaign stored before the plan held it all is read from here).
#include <string>

#include "demcal/v1/campaign.pb.h"
#include "server/plan.hpp"

namespace demcal::server {

/// The plan's structure from the spec; InputError naming the field of a material or an option
/// out of range. Design, responses, targets and fidelity are not filled in.
CampaignPlan read_plan_input(const v1::CampaignSpec& spec);

/// The calibration options of a spec (InputError naming `where`.<field>).
calib::SequentialOptions calibration_options(const v1::CalibrationOptions& spec,
                                             const std::string& where);

/// The diagnosis options of a spec: 0 (proto's unset) takes the default, anything else must be
/// finite and in its range, else InputError naming `where`.<field>.
diagnose::Options diagnose_options(const v1::DiagnoseOptions& options, const std::string& where);

/// The polynomial models the calibration fits: main or 2fi (two-level designs).
doe::ModelKind polynomial_model(const std::string& text, const std::string& where);

}  // namespace demcal::server
