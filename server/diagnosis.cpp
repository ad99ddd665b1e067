#include "server/diagnosis.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string_view>

#include "core/common/error.hpp"
#include "core/diagnose/diagnosis.hpp"
#include "core/doe/nested_fraction.hpp"
#include "core/model/campaign_model.hpp"
#include "core/model/material.hpp"
#include "core/model/preparation.hpp"
#include "server/analysis.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/plan_input.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

/// The material's one median radius as its model states it (real, times sizes.scale; m), 0 for
/// discrete classes, which have none the size distribution states.
double median_radius(const lab::MaterialModel& model) {
  if (const auto* one = std::get_if<particles::Monodisperse>(&model.sizes))
    return one->radius * model.size_scale;
  if (const auto* ln = std::get_if<particles::LogNormal>(&model.sizes))
    return ln->median_radius * model.size_scale;
  return 0.0;
}

/// coarse_graining: what the material says of its particles' size against the powder's, at the
/// design centre (the spec's fixed values, every factor at its centre), and the cohesive
/// parameters (the cohesion slots' in J) the Bond number holds: the particle law's, and the wall
/// law's unless a test instance has a wall law of its own (whose walls then keep their adhesion:
/// a wall path sets every instance's wall law).
void describe_size(const CampaignPlan& plan, diagnose::Problem& p) {
  std::map<std::string, double> centre;
  for (const auto& f : plan.factors) centre[f.path] = f.factor.centre();
  const lab::MaterialModel model =
      lab::with_run_parameters(plan.material, run_parameters(plan, centre, false));
  p.median_radius = median_radius(model);
  p.real_median_radius = model.real_median_radius;
  p.size_scale = model.size_scale;
  const bool own_walls = std::any_of(
      plan.instances.begin(), plan.instances.end(),
      [&](const PlannedInstance& i) { return i.material.wall_law != plan.material.wall_law; });
  for (const auto& info : lab::parameters(model)) {
    const bool cohesion = info.path.starts_with("particle_law.cohesion.") ||
                          (!own_walls && info.path.starts_with("wall_law.cohesion."));
    if (cohesion && info.unit == "J")
      p.bond_scaled[info.path] = lab::get_parameter(model, info.path);
  }
}

/// The instance a response ("instance.metric") is of; nullptr for none.
const PlannedInstance* instance_of(const CampaignPlan& plan, const std::string& response) {
  const auto dot = response.rfind('.');
  for (const auto& i : plan.instances)
    if (dot != std::string::npos && response.compare(0, dot, i.name) == 0 && i.name.size() == dot)
      return &i;
  return nullptr;
}

/// The settings by which an instance consolidates its bed (LabTestInfo::consolidation), at the
/// design's values (the low fidelity level the diagnosis runs at); empty where it does not.
std::map<std::string, double> consolidation_settings(const PlannedInstance& instance) {
  const auto& info = lab::find_lab_info(instance.test);
  std::map<std::string, double> out;
  if (!info.consolidation) return out;
  out[info.consolidation->stress] =
      lab::setting_value(info, instance.settings_low, info.consolidation->stress);
  for (const auto& name : info.consolidation->scaled)
    out[name] = lab::setting_value(info, instance.settings_low, name);
  return out;
}

/// consolidation: a measurement of the solid fraction a consolidation leaves (the density metric
/// of an instance's test), calibrated or held out (then it describes the held-out compact and is
/// left out of the calibration with it), and every other held-out measurement of one instance
/// that consolidates its bed; both instances' consolidation settings are what its runs scale.
void describe_conditioning(const CampaignPlan& plan, diagnose::Problem& p) {
  const Target* density = nullptr;
  const PlannedInstance* measuring = nullptr;
  for (const auto& t : plan.targets) {
    measuring = instance_of(plan, t.response);
    if (!measuring) continue;
    const auto& c = lab::find_lab_info(measuring->test).consolidation;
    if (c && !c->density_metric.empty() &&
        t.response == measuring->name + "." + c->density_metric) {
      density = &t;
      break;
    }
  }
  if (!density) return;
  std::set<const PlannedInstance*> held;
  for (const auto& t : plan.targets)
    if (t.holdout && &t != density) held.insert(instance_of(plan, t.response));
  if (held.size() != 1 || !*held.begin()) return;
  const PlannedInstance& held_out = **held.begin();
  const auto& info = lab::find_lab_info(held_out.test);
  if (!info.consolidation) return;
  diagnose::Conditioning out{held_out.name, info.consolidation->stress, density->response};
  out.scaled[held_out.name] = consolidation_settings(held_out);
  out.scaled[measuring->name] = consolidation_settings(*measuring);
  p.conditioning = std::move(out);
}

}  // namespace

diagnose::Problem make_problem(const CampaignPlan& plan, const std::vector<JobRow>& jobs,
                               std::uint64_t seed) {
  diagnose::Problem p;
  for (const auto& f : plan.factors) p.factors.push_back({f.path, f.factor});
  p.design = plan.design.coded;
  p.responses = plan.responses;
  p.results = response_matrix(plan, jobs);
  for (const auto& t : plan.targets)
    p.measurements.push_back({t.response, t.value, t.weight, t.uncertainty, t.holdout});
  const auto& model = plan.material;
  p.shape_kind = particles::shape_kind_name(model.shape.kind);
  p.rolling_model = model.particle_law.rolling.model;
  p.size_kind = std::holds_alternative<particles::Monodisperse>(model.sizes) ? "monodisperse"
                                                                             : "distribution";
  p.fixed = plan.fixed;
  p.cohesion_model = model.particle_law.cohesion.model;
  p.preparation = lab::preparation_method_name(model.preparation.method);
  // The candidate builds beds from clusters in the instances that take it (their tests build
  // so, no preparation of their own); the others pour as in the design.
  const std::map<std::string, std::string> clusters{{"preparation", "clusters"}};
  p.preparable = std::any_of(plan.instances.begin(), plan.instances.end(), [&](const auto& i) {
    return !lab::instance_switches(i.test, i.material, model, clusters).empty();
  });
  p.agitation_time_max = lab::default_agitation_time(model);
  for (const auto& info : lab::parameters(model)) p.valid[info.path] = {info.lo, info.hi};
  describe_size(plan, p);
  describe_conditioning(plan, p);
  p.options = plan.diagnosis;
  if (p.options.nested) p.nested_rows = doe::main_effect_half(plan.design);
  p.options.seed = seed ? seed : 1;
  return p;
}

namespace {

/// Finished diagnosis rows: a row counts once every test's job of it has ended; a failed job
/// leaves its test's metrics missing (NaN).
std::map<std::string, diagnose::GroupResults> finished_groups(const std::vector<JobRow>& jobs,
                                                              const CampaignPlan& plan) {
  std::map<std::pair<std::string, int>, std::vector<const JobRow*>> rows;
  for (const auto& j : jobs)
    if (job_kind::is_diagnosis(j.kind))
      rows[{job_kind::diagnosis_group(j.kind), j.std_order}].push_back(&j);
  std::map<std::string, diagnose::GroupResults> out;
  for (const auto& [key, row_jobs] : rows) {
    bool ended = true;
    for (const auto* j : row_jobs) ended &= j->state == "done" || j->state == "failed";
    if (!ended) continue;
    auto& values = out[key.first][key.second];
    for (const auto& r : plan.responses) values[r] = diagnose::kPending;
    for (const auto* j : row_jobs)
      if (j->state == "done" && j->metrics_json)
        for (const auto& [metric, value] : metrics_from_json(*j->metrics_json))
          values[j->test + "." + metric] = value;
  }
  return out;
}

// A value the diagnosis does not know yet is NaN (diagnosis.hpp, kPending): its optional field
// stays absent.

v1::DiagnosisMetric metric_message(const diagnose::MetricRow& m) {
  v1::DiagnosisMetric out;
  out.set_response(m.response);
  out.set_target(m.target);
  out.set_holdout(m.holdout);
  out.set_envelope_min(m.envelope_min);
  out.set_envelope_max(m.envelope_max);
  out.set_reachable(m.reachable);
  out.set_statement(m.statement);
  if (std::isfinite(m.curvature_p)) out.set_curvature_p(m.curvature_p);
  out.set_predicted(m.predicted);
  if (std::isfinite(m.simulated)) out.set_simulated(m.simulated);
  if (std::isfinite(m.relative_error)) out.set_relative_error(m.relative_error);
  return out;
}

v1::DiagnosisCandidate candidate_message(const diagnose::CandidateOutcome& c) {
  v1::DiagnosisCandidate out;
  out.set_id(c.id);
  out.set_cause(c.cause);
  out.set_state(c.state);
  out.set_runs(c.runs);
  for (const auto& f : c.factors) {
    auto* m = out.add_factors();
    m->set_path(f.path);
    m->set_low(f.factor.low);
    m->set_high(f.factor.high);
  }
  out.mutable_proposed()->insert(c.proposed.begin(), c.proposed.end());
  out.set_reaches_all(c.reaches_all);
  if (std::isfinite(c.predicted_rms)) out.set_predicted_rms(c.predicted_rms);
  if (std::isfinite(c.verified_rms)) out.set_verified_rms(c.verified_rms);
  if (std::isfinite(c.verified_rms_se)) out.set_verified_rms_se(c.verified_rms_se);
  out.set_rounds(c.rounds);
  out.set_best_round(c.best_round);
  if (std::isfinite(c.design_misprediction)) out.set_design_misprediction(c.design_misprediction);
  for (const auto& [k, v] : c.simulated)  // a run that failed has no value
    if (std::isfinite(v)) (*out.mutable_simulated())[k] = v;
  if (std::isfinite(c.holdout_rms)) out.set_holdout_rms(c.holdout_rms);
  out.set_explains(c.explains);
  out.set_within_noise(c.within_noise);
  out.set_conditioning(c.conditioning);
  if (std::isfinite(c.holdout_rms_se)) out.set_holdout_rms_se(c.holdout_rms_se);
  if (std::isfinite(c.holdout_gain)) out.set_holdout_gain(c.holdout_gain);
  out.set_explains_holdout(c.explains_holdout);
  out.set_explains_label(diagnose::explains_label(c));
  out.set_evidence(c.evidence);
  return out;
}

v1::DiagnosisReport report_message(const diagnose::Report& r) {
  v1::DiagnosisReport out;
  out.set_state(r.state);
  out.set_named_cause(r.named_cause);
  for (const auto& id : r.rivals) out.add_rivals(id);
  out.set_holdout_cause(r.holdout_cause);
  out.set_conclusion(r.conclusion);
  for (const auto& m : r.metrics) *out.add_metrics() = metric_message(m);
  auto* b = out.mutable_baseline();
  b->mutable_proposed()->insert(r.baseline_proposed.begin(), r.baseline_proposed.end());
  if (std::isfinite(r.baseline_predicted_rms)) b->set_predicted_rms(r.baseline_predicted_rms);
  if (std::isfinite(r.baseline_verified_rms)) b->set_verified_rms(r.baseline_verified_rms);
  if (std::isfinite(r.baseline_verified_rms_se)) b->set_verified_rms_se(r.baseline_verified_rms_se);
  if (std::isfinite(r.baseline_holdout_rms)) b->set_holdout_rms(r.baseline_holdout_rms);
  if (std::isfinite(r.baseline_holdout_rms_se)) b->set_holdout_rms_se(r.baseline_holdout_rms_se);
  for (const auto& c : r.conflicts) {
    auto* m = out.add_conflicts();
    m->set_fitted(c.fitted);
    m->set_other(c.other);
    m->set_other_error_alone(c.other_error_alone);
    m->set_other_error_joint(c.other_error_joint);
    m->set_statement(c.statement);
  }
  for (const auto& c : r.candidates) *out.add_candidates() = candidate_message(c);
  return out;
}

/// The runs the diagnosis uses, by kind: the design's, the baseline's verification, and each
/// candidate's augmented design and verification.
std::vector<RunsOfKind> diagnosis_runs(const std::vector<JobRow>& jobs) {
  std::vector<RunsOfKind> kinds{{std::string(job_kind::kDesign), "runs"}};
  std::set<std::string> groups;
  for (const auto& j : jobs)
    if (job_kind::is_diagnosis(j.kind)) groups.insert(job_kind::diagnosis_group(j.kind));
  constexpr std::string_view kVerify = "/verify";
  for (const auto& g : groups) {
    std::string which = g == "baseline" ? "baseline verification runs" : g + " design runs";
    if (g.ends_with(kVerify)) which = g.substr(0, g.size() - kVerify.size()) + " verification runs";
    kinds.push_back({job_kind::diagnosis(g), which});
  }
  return kinds;
}

/// The runs a request of the diagnosis asks for, at the low fidelity level (the level of the design
/// the diagnosis fits): every instance's, or those it names, with the settings it gives them
/// (admitted as a spec's runs are: its settings are not the spec's).
std::vector<PlannedRun> requested_runs(const CampaignPlan& plan, const diagnose::RunRequest& req,
                                       const std::string& kind) {
  auto runs = runs_at(plan, req.parameters, false, req.row, kind,
                      static_cast<std::uint64_t>(req.replicate));
  if (req.tests.empty()) return runs;
  std::erase_if(runs, [&](const PlannedRun& run) {
    return std::find(req.tests.begin(), req.tests.end(), plan.instances[run.instance].name) ==
           req.tests.end();
  });
  for (auto& run : runs)
    if (const auto it = req.settings.find(plan.instances[run.instance].name);
        it != req.settings.end())
      run.settings = it->second;
  admit_runs(plan, runs);
  return runs;
}

/// Under each metric of the report, the flagged values the diagnosis uses for it.
void add_flagged_notes(v1::DiagnosisReport& report, const std::vector<JobRow>& jobs) {
  const auto notes = flagged_notes(jobs, diagnosis_runs(jobs));
  for (auto& m : *report.mutable_metrics())
    if (const auto f = notes.find(m.response()); f != notes.end())
      for (const auto& note : f->second) m.add_notes(note);
}

}  // namespace

CampaignRow with_diagnosis_rounds(Store& store, const CampaignRow& row, int rounds) {
  v1::CampaignSpec spec = spec_from_json(row.spec_json);
  v1::DiagnoseOptions options = spec.diagnose();
  options.set_rounds(rounds);
  int checked = 0;
  try {
    checked = diagnose_options(options, "diagnose").rounds;
  } catch (const InputError& e) {
    throw InputError("rounds", e.message());  // the request's field, not the spec's
  }
  CampaignPlan plan = stored_plan(row);
  if (plan.diagnosis.rounds == checked) return row;
  plan.diagnosis.rounds = checked;
  *spec.mutable_diagnose() = options;
  CampaignRow changed = row;
  changed.spec_json = to_json(spec);
  changed.design_json = plan_to_json(plan);
  store.set_campaign_plan(row.id, changed.spec_json, changed.design_json);
  spdlog::info("campaign {}: diagnosis rounds set to {}", row.id, checked);
  return changed;
}

v1::DiagnoseReply diagnose_campaign(Store& store, const CampaignRow& row, std::uint64_t seed,
                                    bool read_only) {
  v1::DiagnoseReply reply;
  const CampaignPlan plan = stored_plan(row);
  const auto jobs = store.jobs(row.id);
  const auto design = store.counts(row.id, "design");
  if (design.queued + design.leased > 0) {
    reply.set_state("waiting");
    reply.set_conclusion("the design runs are not finished (" + std::to_string(design.done) +
                         " of " + std::to_string(design.total()) + " done)");
    return reply;
  }
  const auto step = diagnose::advance(make_problem(plan, jobs, seed), finished_groups(jobs, plan));
  std::set<std::pair<std::string, int>> stored;
  for (const auto& j : jobs) stored.insert({j.kind, j.std_order});
  std::vector<NewJob> fresh;
  for (const auto& req : step.requests) {
    const std::string kind = job_kind::diagnosis(req.group);
    if (stored.count({kind, req.row})) continue;
    const auto add = jobs_of(plan, requested_runs(plan, req, kind), req.switches);
    fresh.insert(fresh.end(), add.begin(), add.end());
  }
  if (read_only) fresh.clear();
  if (!fresh.empty()) {
    take_held_points(store, fresh);
    store.add_jobs(row.id, fresh);
    spdlog::info("campaign {}: diagnosis queued {} jobs", row.id, fresh.size());
  }
  reply.set_state(step.report.state);
  reply.set_named_cause(step.report.named_cause);
  reply.set_conclusion(step.report.conclusion);
  *reply.mutable_report() = report_message(step.report);
  add_flagged_notes(*reply.mutable_report(), jobs);
  reply.set_jobs_queued(static_cast<int>(fresh.size()));
  return reply;
}

}  // namespace demcal::server
