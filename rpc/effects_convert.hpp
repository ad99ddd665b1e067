#pragma once
// One response's analysis (core/doe/analysis.hpp) as the MetricEffects message that `demcal
// effects` prints: the coordinator's GetEffects and the offline `demcal analyze` share it, and
// with it one effects printer (client/service_client.hpp, print_effects).
#include <string>

#include "core/doe/analysis.hpp"
#include "demcal/v1/campaign.pb.h"

namespace demcal::rpc {

/// Effects largest first, Lenth's PSE/ME/SME, the fit's coefficients, noise and curvature.
v1::MetricEffects effects_message(const std::string& response, const doe::ResponseAnalysis& a);

}  // namespace demcal::rpc
