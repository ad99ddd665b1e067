#pragma once
// Analysis on demand: the stored results of a campaign as a response matrix in design order,
// effects through core/doe, and calibration against the measured targets through core/calib.
#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "core/calib/calibration.hpp"
#include "core/doe/analysis.hpp"
#include "server/plan.hpp"
#include "server/store.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {

/// One row per design row (standard order), one column per plan.responses; NaN = no result.
/// Per response ("test.metric"), the design runs (std order) whose value is flagged: a phase it
/// is computed from did not reach its target.
std::map<std::string, std::vector<int>> flagged_runs(const std::vector<JobRow>& jobs);
/// `kind` selects the jobs: the campaign's design, or a calibration stage's ("stage:<n>"),
/// whose rows are the same design laid over the stage's box.
Eigen::MatrixXd response_matrix(const CampaignPlan& plan, const std::vector<JobRow>& jobs,
                                std::string_view kind = job_kind::kDesign);

doe::ResponseAnalysis analyse(const CampaignPlan& plan, const Eigen::VectorXd& y,
                              doe::ModelKind model, double alpha);

}  // namespace demcal::server
