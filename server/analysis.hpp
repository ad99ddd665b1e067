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
/// `kind` selects the jobs: the campaign's design, or a calibration stage's ("stage:<n>"),
/// whose rows are the same design laid over the stage's box.
Eigen::MatrixXd response_matrix(const CampaignPlan& plan, const std::vector<JobRow>& jobs,
                                std::string_view kind = job_kind::kDesign);

/// Per response ("test.metric"), the runs (std order) of the jobs of `kind`, as for
/// response_matrix, whose value is flagged: a phase it is computed from did not reach its target.
std::map<std::string, std::vector<int>> flagged_runs(const std::vector<JobRow>& jobs,
                                                     std::string_view kind = job_kind::kDesign);

/// What a reader is told of a metric's flagged runs wherever their values are used (effects,
/// calibration): "flagged runs 3, 7: ..." with the command that shows each reason; `which`
/// names the runs ("runs", "high-level runs", ...).
std::string flagged_runs_note(const std::vector<int>& runs, const std::string& which = "runs");

/// A kind of job whose values an analysis uses, and the words that name its runs in a note.
struct RunsOfKind {
  std::string kind;
  std::string which;
};

/// Per response, one flagged_runs_note per kind of `kinds` whose runs carry a flag for it.
std::map<std::string, std::vector<std::string>> flagged_notes(const std::vector<JobRow>& jobs,
                                                              const std::vector<RunsOfKind>& kinds);

doe::ResponseAnalysis analyse(const CampaignPlan& plan, const Eigen::VectorXd& y,
                              doe::ModelKind model, double alpha);

}  // namespace demcal::server
