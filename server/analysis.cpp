#include "server/analysis.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace demcal::server {

Eigen::MatrixXd response_matrix(const CampaignPlan& plan, const std::vector<JobRow>& jobs,
                                std::string_view kind) {
  Eigen::MatrixXd y = Eigen::MatrixXd::Constant(
      plan.design.runs(), static_cast<Eigen::Index>(plan.responses.size()), std::nan(""));
  for (const auto& job : jobs) {
    if (job.kind != kind || job.state != "done" || !job.metrics_json) continue;
    if (job.std_order < 1 || job.std_order > plan.design.runs()) continue;
    for (const auto& [metric, value] : metrics_from_json(*job.metrics_json)) {
      const std::string name = job.test + "." + metric;
      for (std::size_t c = 0; c < plan.responses.size(); ++c)
        if (plan.responses[c] == name) y(job.std_order - 1, Eigen::Index(c)) = value;
    }
  }
  return y;
}

std::map<std::string, std::vector<int>> flagged_runs(const std::vector<JobRow>& jobs,
                                                     std::string_view kind) {
  std::map<std::string, std::vector<int>> out;
  for (const auto& job : jobs) {
    if (job.kind != kind || job.state != "done") continue;
    for (const auto& [metric, why] : flags_from_json(job.flags_json))
      out[job.test + "." + metric].push_back(job.std_order);
  }
  return out;
}

std::string flagged_runs_note(const std::vector<int>& runs, const std::string& which) {
  std::string list;
  for (int r : runs) list += (list.empty() ? "" : ", ") + std::to_string(r);
  return "flagged " + which + " " + list +
         ": a phase this metric is computed from did not reach its target (demcal status --jobs)";
}

std::map<std::string, std::vector<std::string>> flagged_notes(
    const std::vector<JobRow>& jobs, const std::vector<RunsOfKind>& kinds) {
  std::map<std::string, std::vector<std::string>> out;
  for (const auto& k : kinds)
    for (const auto& [response, runs] : flagged_runs(jobs, k.kind))
      out[response].push_back(flagged_runs_note(runs, k.which));
  return out;
}

doe::ResponseAnalysis analyse(const CampaignPlan& plan, const Eigen::VectorXd& y,
                              doe::ModelKind model, double alpha) {
  doe::AnalysisOptions o;
  o.model = model;
  o.alpha = alpha;
  for (const auto& f : plan.factors) o.factors.push_back(f.factor);
  return doe::analyse_response(plan.design.coded, y, o);
}

}  // namespace demcal::server
