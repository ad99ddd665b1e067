#include "server/plan.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/common/error.hpp"
#include "core/doe/minimum_aberration.hpp"
#include "core/doe/nested_fraction.hpp"
#include "core/model/campaign_model.hpp"
#include "rpc/material_convert.hpp"
#include "server/admission.hpp"
#include "server/convert.hpp"
#include "server/limits.hpp"
#include "server/plan_input.hpp"

namespace demcal::server {
namespace {

std::string idx(const std::string& field, int i) {
  return field + "[" + std::to_string(i) + "]";
}

/// Limits on what one submission can ask the coordinator to build and store (limits.hpp):
/// centre points and replicates each within their range, and the campaign's jobs (design rows x
/// replicates x tests) at most kMaxCampaignJobs, so a submission cannot stall the store's lock or
/// its disk.
void check_repeats(const v1::Design& d, int runs, int tests) {
  if (d.centre_points() < 0 || d.centre_points() > kMaxCentrePoints)
    throw InputError("spec.design.centre_points",
                     "must be in [0, " + std::to_string(kMaxCentrePoints) + "]");
  if (d.replicates() < 0 || d.replicates() > kMaxReplicates)
    throw InputError("spec.design.replicates",
                     "must be in [0, " + std::to_string(kMaxReplicates) + "]");
  const long jobs = static_cast<long>(runs + d.centre_points()) * std::max(1, d.replicates()) *
                    std::max(1, tests);
  if (jobs > kMaxCampaignJobs)
    throw InputError("spec.design", std::to_string(jobs) +
                                        " jobs (runs and centre points x "
                                        "replicates x tests); at most " +
                                        std::to_string(kMaxCampaignJobs) + " per campaign");
}

/// Checks an instance name: responses are "<name>.<metric>", so no dots, and a name a shell and
/// a CSV header carry as it is.
void check_instance_name(const std::string& name, const std::string& where) {
  const bool ok =
      !name.empty() && name.size() <= 64 &&
      name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos;
  if (!ok)
    throw InputError(where, "'" + echo(name) + "' is not an instance name (1-64 of a-z, 0-9, _)");
}

/// The structure of the test instances: names unique and well formed, threads in range, and each
/// instance's material (its own wall law's errors named at its field).
void check_instances(const v1::CampaignSpec& spec) {
  if (spec.tests_size() == 0) throw InputError("spec.tests", "a campaign needs at least one test");
  std::set<std::string> seen;
  for (int i = 0; i < spec.tests_size(); ++i) {
    const auto& t = spec.tests(i);
    const std::string where = "spec." + idx("tests", i);
    const std::string name = rpc::instance_name(t);
    if (!t.name().empty()) check_instance_name(t.name(), where + ".name");
    if (!seen.insert(name).second)
      throw InputError(where + (t.name().empty() ? ".test" : ".name"),
                       "test '" + name + "' appears twice (give each instance its own `name`)");
    if (t.threads() < 0 || t.threads() > kMaxThreads)
      throw InputError(where + ".threads", "must be in [0, " + std::to_string(kMaxThreads) +
                                               "] (a worker runs at most its own --threads)");
  }
}

/// The run count the spec's design asks for: a power of two in [k + 1, 2^k].
int design_runs(const v1::Design& d, int k) {
  const int full = 1 << k;
  int runs = d.runs() ? d.runs() : full;
  if (d.type() == v1::Design::FULL_FACTORIAL) {
    if (d.runs() && d.runs() != full)
      throw InputError("spec.design.runs", "a full factorial of " + std::to_string(k) +
                                               " factors has " + std::to_string(full) + " runs");
    runs = full;
  }
  if (runs < 2 || (runs & (runs - 1)) != 0 || runs > full)
    throw InputError("spec.design.runs", std::to_string(runs) + " is not a power of two in [2, 2^" +
                                             std::to_string(k) + "]");
  if (runs <= k)
    throw InputError("spec.design.runs", std::to_string(runs) + " runs cannot estimate " +
                                             std::to_string(k) + " main effects (need at least " +
                                             std::to_string(k + 1) + ")");
  return runs;
}

void plan_design(const v1::CampaignSpec& spec, CampaignPlan& plan) {
  if (spec.factors_size() == 0) throw InputError("spec.factors", "a campaign needs factors");
  if (spec.factors_size() > doe::kMaxFactors)
    throw InputError("spec.factors", "at most " + std::to_string(doe::kMaxFactors) + " factors");
  const int k = spec.factors_size();
  const auto& d = spec.design();
  const int runs = design_runs(d, k);
  check_repeats(d, runs, spec.tests_size());
  try {
    if (!d.generators().empty()) {
      plan.design = doe::fractional_factorial(k, d.generators());
      if (plan.design.runs() != runs)
        throw InputError("", "the generators give " + std::to_string(plan.design.runs()) +
                                 " runs, not " + std::to_string(runs));
    } else {
      plan.design =
          runs == (1 << k) ? doe::full_factorial(k) : doe::minimum_aberration_design(k, runs);
    }
  } catch (const InputError& e) {
    throw InputError(d.generators().empty() ? "spec.design.runs" : "spec.design.generators",
                     e.message());
  }
  for (std::size_t i = 0; i < plan.factors.size(); ++i)
    plan.design.factor_names[i] = plan.factors[i].factor.name;
  doe::add_centre_points(plan.design, d.centre_points());
  doe::replicate_runs(plan.design, d.replicates() ? d.replicates() : 1);
  if (d.seed()) doe::randomise_run_order(plan.design, d.seed());
}

/// The measurements as calibration targets: each names one response of the campaign.
void plan_targets(const v1::CampaignSpec& spec, CampaignPlan& plan) {
  std::set<std::string> tests;
  for (const auto& i : plan.instances) tests.insert(i.name);
  for (int i = 0; i < spec.measurements_size(); ++i) {
    const auto& m = spec.measurements(i);
    const std::string where = "spec." + idx("measurements", i);
    std::vector<std::string> matches;
    for (const auto& r : plan.responses) {
      const auto dot = r.find('.');
      if (r.substr(dot + 1) == m.metric() && (m.test().empty() || r.substr(0, dot) == m.test()))
        matches.push_back(r);
    }
    if (!m.test().empty() && !tests.count(m.test()))
      throw InputError(where + ".test",
                       "'" + echo(m.test()) + "' is not one of the campaign's tests");
    if (matches.empty())
      throw InputError(where + ".metric", "no test of the campaign reports '" + m.metric() + "'");
    if (matches.size() > 1)
      throw InputError(where + ".test",
                       "metric '" + m.metric() + "' is reported by several tests: name the test");
    if (!std::isfinite(m.value()) || m.value() == 0.0)
      throw InputError(where + ".value", "must be finite and non-zero (errors are relative)");
    if (!(std::isfinite(m.uncertainty()) && m.uncertainty() >= 0))
      throw InputError(where + ".uncertainty", "must be finite and >= 0");
    if (!(std::isfinite(m.weight()) && m.weight() >= 0))
      throw InputError(where + ".weight", "must be finite and >= 0");
    Target t{matches.front(), m.value(),  m.weight() > 0 ? m.weight() : 1.0,
             std::nullopt,    m.source(), m.holdout()};
    if (m.uncertainty() > 0) t.uncertainty = m.uncertainty();
    plan.targets.push_back(t);
  }
}

/// The high rows the coordinator chooses: the first centre point, and the smallest fraction
/// nested in the design that still estimates every main effect when it is smaller than the
/// design (else the centre point alone; a design without centre points: that fraction).
std::vector<int> default_high_rows(const doe::Design& d) {
  const std::vector<int> fraction = doe::nested_fraction(d, d.factors() + 1);
  std::vector<int> rows;
  int factorial = 0, centre = -1;
  for (int r = 0; r < d.runs(); ++r) {
    const auto type = d.point_type[std::size_t(r)];
    if (type == doe::PointType::kFactorial && d.replicate[std::size_t(r)] == 1) ++factorial;
    if (type == doe::PointType::kCentre && centre < 0) centre = r;
  }
  if (centre < 0 || static_cast<int>(fraction.size()) < factorial)
    for (const int r : fraction) rows.push_back(r + 1);
  if (centre >= 0) rows.push_back(centre + 1);
  return rows;
}

std::vector<int> planned_high_rows(const v1::Fidelity& f, const doe::Design& d) {
  if (f.high_rows().empty()) return default_high_rows(d);
  std::set<int> seen;
  for (int i = 0; i < f.high_rows_size(); ++i) {
    const int r = f.high_rows(i);
    const std::string where = "spec.fidelity." + idx("high_rows", i);
    if (r < 1 || r > d.runs())
      throw InputError(where, std::to_string(r) + " is not a design row (1.." +
                                  std::to_string(d.runs()) + ", standard order)");
    if (!seen.insert(r).second) throw InputError(where, "row " + std::to_string(r) + " twice");
  }
  return {f.high_rows().begin(), f.high_rows().end()};
}

/// The fidelity axis's form: a path, two distinct finite levels, the high rows, and the jobs
/// they add (what the levels may be is the material side's: lab::model_campaign).
void plan_fidelity(const v1::CampaignSpec& spec, CampaignPlan& plan) {
  if (!spec.has_fidelity()) return;
  const auto& f = spec.fidelity();
  if (f.path().empty()) throw InputError("spec.fidelity.path", "missing");
  if (!std::isfinite(f.low())) throw InputError("spec.fidelity.low", "must be finite");
  if (!std::isfinite(f.high())) throw InputError("spec.fidelity.high", "must be finite");
  if (f.low() == f.high())
    throw InputError("spec.fidelity.high",
                     "must differ from low (" + message_number(f.low()) + ")");
  plan.fidelity = FidelityPlan{f.path(), f.low(), f.high(), planned_high_rows(f, plan.design)};
  const long jobs = static_cast<long>(plan.design.runs() + plan.fidelity->high_rows.size()) *
                    std::max(1, spec.tests_size());
  if (jobs > kMaxCampaignJobs)
    throw InputError("spec.fidelity.high_rows",
                     std::to_string(jobs) + " jobs with the high rows; at most " +
                         std::to_string(kMaxCampaignJobs) + " per campaign");
}

/// The bytes the campaign's jobs would store at most kMaxCampaignPayloadBytes: the material is
/// copied into every job, so its size times the jobs, checked before any job is built.
void check_campaign_bytes(const CampaignPlan& plan) {
  const std::size_t rows =
      std::size_t(plan.design.runs()) + (plan.fidelity ? plan.fidelity->high_rows.size() : 0);
  const std::size_t jobs = rows * std::max<std::size_t>(1, plan.instances.size());
  const std::size_t material = to_json(rpc::to_material_message(plan.material)).size();
  if (jobs * material > kMaxCampaignPayloadBytes)
    throw InputError("spec.material",
                     std::to_string(material) + " bytes copied into each of " +
                         std::to_string(jobs) + " jobs, more than the " +
                         std::to_string(kMaxCampaignPayloadBytes / kMiB) +
                         " MiB a campaign may store (fewer size classes or fewer jobs)");
}

/// The material side of the plan as lab::model_campaign checks it, with the design's runs.
lab::CampaignModel campaign_model(const CampaignPlan& plan) {
  lab::CampaignModel c;
  c.material = plan.material;
  for (const auto& [path, value] : plan.fixed)
    c.fixed.push_back({path, value, "spec.fixed." + path});
  for (std::size_t i = 0; i < plan.instances.size(); ++i) {
    const auto& p = plan.instances[i];
    c.instances.push_back(
        {p.name, p.test, p.settings_low, p.material, p.seed, "spec." + idx("tests", int(i))});
  }
  for (std::size_t i = 0; i < plan.factors.size(); ++i) {
    const auto& f = plan.factors[i];
    c.factors.push_back({f.path, f.factor.low, f.factor.high, f.factor.scale == doe::Scale::kLog,
                         f.tied, "spec." + idx("factors", int(i))});
  }
  if (plan.fidelity) c.fidelity = {plan.fidelity->path, plan.fidelity->low, plan.fidelity->high};
  for (const auto& run : design_runs(plan, plan.factors, std::string(job_kind::kDesign), 0, false))
    if (run.instance == 0) c.runs.push_back({run.std_order, false, run.parameters});
  if (plan.fidelity)
    for (const auto& run : design_runs(plan, plan.factors, std::string(job_kind::kHighDesign), 0,
                                       true, &plan.fidelity->high_rows))
      if (run.instance == 0) c.runs.push_back({run.std_order, true, run.parameters});
  return c;
}

/// What the catalogue says of each instance: its responses and its settings at both levels.
void apply_model(const std::vector<lab::ModelledInstance>& modelled, CampaignPlan& plan) {
  for (std::size_t i = 0; i < plan.instances.size(); ++i) {
    auto& p = plan.instances[i];
    p.settings_low = modelled[i].low;
    p.settings_high = modelled[i].high;
    p.waits_for = modelled[i].waits_for;
    for (const auto& m : modelled[i].metrics) plan.responses.push_back(p.name + "." + m);
  }
}

}  // namespace

std::vector<std::string> instance_names(const CampaignPlan& plan) {
  std::vector<std::string> out;
  for (const auto& i : plan.instances) out.push_back(i.name);
  return out;
}

CampaignPlan plan_campaign(const v1::CampaignSpec& spec, std::vector<NewJob>& jobs) {
  check_fields(spec, "spec");
  if (spec.name().empty()) throw InputError("spec.name", "missing");
  check_printable(spec.name(), "spec.name");
  if (!spec.has_material()) throw InputError("spec.material", "missing");
  check_instances(spec);
  CampaignPlan plan = read_plan_input(spec);
  plan_design(spec, plan);
  plan_fidelity(spec, plan);
  check_campaign_bytes(plan);
  apply_model(lab::model_campaign(campaign_model(plan)), plan);
  plan_targets(spec, plan);
  jobs = jobs_of(plan, design_runs(plan, plan.factors, std::string(job_kind::kDesign), 0, false));
  if (plan.fidelity) {
    const auto high =
        jobs_of(plan, design_runs(plan, plan.factors, std::string(job_kind::kHighDesign), 0, true,
                                  &plan.fidelity->high_rows));
    jobs.insert(jobs.end(), high.begin(), high.end());
  }
  return plan;
}

}  // namespace demcal::server
