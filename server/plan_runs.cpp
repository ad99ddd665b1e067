// The runs of a plan and the jobs that simulate them (plan.hpp).
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/model/campaign_model.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/run_key.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

/// The simulation seed of design row `row` (0-based, standard order) of an instance whose first
/// row has `seed`: its own by default, so that repeated points (centre points, replicates)
/// measure the run-to-run noise; pinned, a repeated point shares its replicate's seed.
std::uint64_t design_seed(const CampaignPlan& plan, std::uint64_t seed, int row) {
  const int offset = plan.pinned_seeds ? plan.design.replicate[std::size_t(row)] - 1 : row;
  return seed + static_cast<std::uint64_t>(offset);
}

v1::JobSpec job_spec(const CampaignPlan& plan, const PlannedRun& run,
                     const v1::Material& material) {
  const auto& instance = plan.instances[run.instance];
  v1::JobSpec job;
  job.set_test(instance.test);
  for (const auto& [name, value] : run_settings(plan, run)) (*job.mutable_settings())[name] = value;
  *job.mutable_material() = material;
  for (const auto& [path, value] : run.parameters) (*job.mutable_parameters())[path] = value;
  job.set_seed(run.seed);
  job.set_threads(instance.threads);
  return job;
}

}  // namespace

lab::Settings run_settings(const CampaignPlan& plan, const PlannedRun& run) {
  const auto& instance = plan.instances[run.instance];
  lab::Settings out = run.high ? instance.settings_high : instance.settings_low;
  for (const auto& [name, value] : run.settings) out[name] = value;
  return out;
}

std::map<std::string, double> run_parameters(const CampaignPlan& plan,
                                             const std::map<std::string, double>& factors,
                                             bool high) {
  std::map<std::string, double> out = plan.fixed;
  const auto& f = plan.fidelity;
  if (f && !f->path.starts_with(lab::kSettingsPrefix)) out[f->path] = high ? f->high : f->low;
  for (const auto& [path, value] : factors) out[path] = value;
  for (const auto& factor : plan.factors)
    if (const auto it = factors.find(factor.path); it != factors.end())
      for (const auto& tied : factor.tied) out[tied] = it->second;
  return out;
}

std::vector<PlannedRun> design_runs(const CampaignPlan& plan, const std::vector<PlannedFactor>& box,
                                    const std::string& kind, int stage_offset, bool high,
                                    const std::vector<int>* rows) {
  std::vector<PlannedRun> runs;
  const auto& design = plan.design;
  for (int r = 0; r < design.runs(); ++r) {
    if (rows && std::find(rows->begin(), rows->end(), r + 1) == rows->end()) continue;
    std::map<std::string, double> factors;
    for (std::size_t f = 0; f < box.size(); ++f)
      factors[box[f].path] = box[f].factor.to_natural(design.coded(r, Eigen::Index(f)));
    const auto parameters = run_parameters(plan, factors, high);
    for (std::size_t i = 0; i < plan.instances.size(); ++i) {
      const std::uint64_t seed = design_seed(plan, plan.instances[i].seed, r) +
                                 (plan.pinned_seeds ? 0 : static_cast<std::uint64_t>(stage_offset));
      runs.push_back({i, r + 1, design.run_order[std::size_t(r)], kind, parameters, high, seed});
    }
  }
  return runs;
}

std::vector<PlannedRun> runs_at(const CampaignPlan& plan,
                                const std::map<std::string, double>& factors, bool high,
                                int std_order, const std::string& kind, std::uint64_t seed_offset) {
  std::vector<PlannedRun> runs;
  const auto parameters = run_parameters(plan, factors, high);
  for (std::size_t i = 0; i < plan.instances.size(); ++i)
    runs.push_back({i, std_order, static_cast<int>(i) + 1, kind, parameters, high,
                    plan.instances[i].seed + seed_offset});
  return runs;
}

namespace {

/// A run of an instance that takes none of the diagnosis's switches is the design's run at the
/// same point when the design has one (its factors at the same levels, among `design`): the same
/// parameters and seed, so the store hands its result back instead of simulating it again. A
/// replicate after the first (a seed other than the instance's own) keeps its seed, so its noise
/// stays its own.
void share_design_run(const CampaignPlan& plan, const std::vector<PlannedRun>& design,
                      PlannedRun& run) {
  if (run.seed != plan.instances[run.instance].seed) return;
  for (const auto& d : design)
    if (d.instance == run.instance && d.parameters == run.parameters) {
      run.seed = d.seed;
      return;
    }
}

}  // namespace

std::vector<NewJob> jobs_of(const CampaignPlan& plan, const std::vector<PlannedRun>& runs,
                            const std::map<std::string, std::string>& switches) {
  // Each instance's switches and material in proto form once, not once a job.
  std::vector<std::map<std::string, std::string>> taken;
  std::vector<v1::Material> materials;
  for (const auto& instance : plan.instances) {
    taken.push_back(
        lab::instance_switches(instance.test, instance.material, plan.material, switches));
    materials.push_back(rpc::to_material_message(
        taken.back().empty() ? instance.material
                             : lab::with_switches(instance.material, taken.back())));
  }
  std::vector<NewJob> jobs;
  std::optional<std::vector<PlannedRun>> design;  // the design's runs, once one is looked for
  for (PlannedRun run : runs) {
    const auto& own = taken[run.instance];
    if (own.size() != switches.size()) {
      run.parameters = lab::taken_parameters(run.parameters, switches, own);
      if (own.empty()) {
        if (!design) design = design_runs(plan, plan.factors, run.kind, 0, run.high);
        share_design_run(plan, *design, run);
      }
    }
    const v1::JobSpec job = job_spec(plan, run, materials[run.instance]);
    const auto& instance = plan.instances[run.instance];
    jobs.push_back({run.std_order, run.run_order, instance.name, run.kind, to_json(job),
                    run_key(job), instance.waits_for});
  }
  return jobs;
}

namespace {

/// Whether two points have the same parameter paths and every value within kHeldPointTolerance.
bool near_point(const google::protobuf::Map<std::string, double>& proposed,
                const std::map<std::string, double>& held) {
  if (proposed.size() != held.size()) return false;
  for (const auto& [path, value] : proposed) {
    const auto other = held.find(path);
    if (other == held.end()) return false;
    const double scale = std::max(std::abs(value), std::abs(other->second));
    if (!(std::abs(value - other->second) <= kHeldPointTolerance * scale)) return false;
  }
  return true;
}

}  // namespace

void take_held_points(Store& store, std::vector<NewJob>& jobs) {
  for (auto& job : jobs) {
    if (job.run_key.key.empty() || store.holds_run(job.run_key.key)) continue;
    const v1::JobSpec proposed = job_from_payload(job.payload);
    for (const auto& held :
         store.journal_runs_at(proposed.test(), std::to_string(proposed.seed()))) {
      const auto point = metrics_from_json(held.parameters_json);
      if (!near_point(proposed.parameters(), point)) continue;
      v1::JobSpec at_held = proposed;
      at_held.mutable_parameters()->clear();
      at_held.mutable_parameters()->insert(point.begin(), point.end());
      RunKey key = run_key(at_held);
      if (key.key != held.run_key) continue;
      job.payload = to_json(at_held);
      job.run_key = std::move(key);
      break;
    }
  }
}

void admit_runs(const CampaignPlan& plan, const std::vector<PlannedRun>& runs) {
  for (const auto& run : runs) {
    const auto& instance = plan.instances[run.instance];
    const std::string where = "spec.tests[" + std::to_string(run.instance) + "]";
    lab::admit_run(instance.test, instance.material, run.parameters, run_settings(plan, run),
                   lab::instance_fields(where, instance.material, plan.material), run.std_order);
  }
}

}  // namespace demcal::server
