#include "server/convert.hpp"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string_view>

#include "core/common/error.hpp"
#include "core/doe/alias_structure.hpp"
#include "core/doe/minimum_aberration.hpp"
#include "core/doe/nested_fraction.hpp"
#include "core/model/catalog.hpp"
#include "rpc/effects_convert.hpp"
#include "rpc/material_convert.hpp"
#include "server/admission.hpp"
#include "server/calibration.hpp"
#include "server/diagnosis.hpp"
#include "server/limits.hpp"
#include "server/run_key.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

namespace {

std::string idx(const std::string& field, int i) {
  return field + "[" + std::to_string(i) + "]";
}

std::uint64_t base_seed(const v1::LabTest& t) {
  return t.seed() ? t.seed() : 1;
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

/// The simulation seed of design row `row` (0-based, standard order): its own by default, so
/// that repeated points (centre points, replicates) measure the run-to-run noise.
std::uint64_t design_seed(const v1::LabTest& t, const v1::Design& design, const doe::Design& d,
                          int row) {
  if (design.simulation_seeds() == v1::Design::PINNED)
    return base_seed(t) + static_cast<std::uint64_t>(d.replicate[std::size_t(row)] - 1);
  return base_seed(t) + static_cast<std::uint64_t>(row);
}

/// The material a test instance runs with: `material` with the instance's own wall law, if any.
v1::Material instance_material(const v1::Material& material, const v1::LabTest& t) {
  v1::Material m = material;
  if (t.has_wall_law()) *m.mutable_wall_law() = t.wall_law();
  return m;
}

/// One job of a test instance: the lab test to run, its settings and material, the parameters
/// (the spec's fixed ones, then `parameters`) and the simulation seed.
v1::JobSpec instance_job(const v1::CampaignSpec& spec, const v1::LabTest& t,
                         const v1::Material& material,
                         const std::map<std::string, double>& parameters, std::uint64_t seed) {
  v1::JobSpec job;
  job.set_test(t.test());
  *job.mutable_settings() = t.settings();
  *job.mutable_material() = instance_material(material, t);
  for (const auto& [path, value] : rpc::run_parameters(spec, parameters))
    (*job.mutable_parameters())[path] = value;
  job.set_seed(seed);
  job.set_threads(t.threads());
  return job;
}

/// Every rule a worker checks before it simulates the job, at the job's own material: a factor
/// can change what a test asks for (the drum's particle count with the particle radius).
void admit_job(const v1::JobSpec& job, const std::string& where, int row) {
  try {
    lab::admit_lab_test(job.test(), rpc::job_material(job), rpc::to_settings(job.settings()),
                        {where + ".settings", "spec.material"});
  } catch (const InputError& e) {
    throw InputError(e.where(), "design run " + std::to_string(row) + ": " + e.message());
  }
}

/// A job to store: the planned job's payload with its run key.
NewJob new_job(int std_order, int run_order, const std::string& instance, const std::string& kind,
               const v1::JobSpec& job) {
  return {std_order, run_order, instance, kind, to_json(job), run_key(job)};
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

/// The model of a test instance: the campaign's with the instance's wall law; errors in that law
/// name the instance's field.
lab::MaterialModel instance_model(const v1::CampaignSpec& spec, const v1::LabTest& t,
                                  const std::string& where) {
  try {
    return rpc::to_material_model(instance_material(spec.material(), t), "spec.material");
  } catch (const InputError& e) {
    const std::string base = "spec.material.wall_law";
    if (!t.has_wall_law() || e.where().rfind(base, 0) != 0) throw;
    throw InputError(where + ".wall_law" + e.where().substr(base.size()), e.message());
  }
}

}  // namespace

std::string instance_name(const v1::LabTest& t) {
  return t.name().empty() ? t.test() : t.name();
}

std::string to_json(const google::protobuf::Message& message) {
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.preserve_proto_field_names = true;
  (void)google::protobuf::util::MessageToJsonString(message, &out, o);
  return out;
}

void from_json(const std::string& json, google::protobuf::Message& message) {
  google::protobuf::util::JsonParseOptions o;
  o.case_insensitive_enum_parsing = true;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &message, o);
  if (!status.ok()) throw InputError("", std::string(status.message()));
}

namespace {

/// A test instance of the spec: its name and material (its own wall law, if it has one).
using Instances = std::vector<std::pair<std::string, lab::MaterialModel>>;

/// Validates the tests and their settings; the responses "<instance>.<metric>" in order.
Instances plan_tests(const v1::CampaignSpec& spec, CampaignPlan& plan) {
  if (spec.tests_size() == 0) throw InputError("spec.tests", "a campaign needs at least one test");
  std::set<std::string> seen;
  Instances instances;
  for (int i = 0; i < spec.tests_size(); ++i) {
    const auto& t = spec.tests(i);
    const std::string where = "spec." + idx("tests", i);
    const lab::LabTestInfo* info = nullptr;
    try {
      info = &lab::find_lab_info(t.test());
    } catch (const InputError& e) {
      throw InputError(where + ".test", e.message());
    }
    const std::string name = instance_name(t);
    if (!t.name().empty()) check_instance_name(t.name(), where + ".name");
    if (!seen.insert(name).second)
      throw InputError(where + (t.name().empty() ? ".test" : ".name"),
                       "test '" + name + "' appears twice (give each instance its own `name`)");
    if (t.threads() < 0 || t.threads() > kMaxThreads)
      throw InputError(where + ".threads", "must be in [0, " + std::to_string(kMaxThreads) +
                                               "] (a worker runs at most its own --threads)");
    lab::MaterialModel instance = instance_model(spec, t, where);
    lab::admit_lab_test(t.test(), instance, rpc::to_settings(t.settings()),
                        {where + ".settings", "spec.material"});
    instances.emplace_back(name, std::move(instance));
    plan.tests.push_back(name);
    for (const auto& m : info->metrics) plan.responses.push_back(name + "." + m.name);
  }
  return instances;
}

/// Sets the spec's fixed parameters on the material and on every instance.
void apply_fixed(const v1::CampaignSpec& spec, lab::MaterialModel& model, Instances& instances) {
  std::vector<lab::ParameterValue> fixed;
  for (const auto& [path, value] :
       std::map<std::string, double>(spec.fixed().begin(), spec.fixed().end()))
    fixed.push_back({path, value, "spec.fixed." + path});
  model = lab::with_parameters(std::move(model), fixed);
  for (auto& [name, instance] : instances) {
    for (const auto& f : fixed)
      if (!lab::has_parameter(instance, f.path))
        throw InputError(f.where,
                         "not a parameter of test '" + name + "' (its own wall_law lacks it)");
    instance = lab::with_parameters(std::move(instance), fixed);
  }
}

/// A factor's bounds: finite, ordered, inside the parameter's valid range, > 0 on a log scale.
void check_factor_bounds(const v1::Factor& f, const lab::ParameterInfo& info,
                         const std::string& where) {
  if (!std::isfinite(f.low())) throw InputError(where + ".low", "must be finite");
  if (!std::isfinite(f.high())) throw InputError(where + ".high", "must be finite");
  if (!(f.low() < f.high()))
    throw InputError(where + ".high", "must be above low (" + fmt(f.low()) + ")");
  const std::string range =
      " the valid range [" + fmt(info.lo) + ", " + fmt(info.hi) + "] " + info.unit;
  if (f.low() < info.lo) throw InputError(where + ".low", fmt(f.low()) + " is below" + range);
  if (f.high() > info.hi) throw InputError(where + ".high", fmt(f.high()) + " is above" + range);
  if (f.scale() == v1::Factor::LOG && !(f.low() > 0))
    throw InputError(where + ".low", "must be > 0 on a log scale");
}

/// A factor's tied paths: each a parameter of the material and of every instance, taking both
/// of the factor's bounds, and set by nothing else (no factor, no fixed value, no other tie).
void plan_tied(const v1::CampaignSpec& spec, const v1::Factor& f, const lab::MaterialModel& model,
               const Instances& instances, const std::string& where, std::set<std::string>& seen) {
  for (int i = 0; i < f.tied_size(); ++i) {
    const std::string& path = f.tied(i);
    const std::string at = where + "." + idx("tied", i);
    lab::require_parameter(model, path, at);
    const bool a_factor = std::any_of(spec.factors().begin(), spec.factors().end(),
                                      [&](const v1::Factor& g) { return g.path() == path; });
    if (a_factor || spec.fixed().count(path) || !seen.insert(path).second)
      throw InputError(at, "'" + path + "' is set twice (a factor, a fixed value or another tie)");
    lab::with_parameters(model, {{path, f.low(), at}, {path, f.high(), at}});
    for (const auto& [name, instance] : instances)
      if (!lab::has_parameter(instance, path))
        throw InputError(at, "'" + path + "' is not a parameter of test '" + name +
                                 "' (its own wall_law lacks it)");
  }
}

void plan_factors(const v1::CampaignSpec& spec, const lab::MaterialModel& model,
                  const Instances& instances, CampaignPlan& plan) {
  if (spec.factors_size() == 0) throw InputError("spec.factors", "a campaign needs factors");
  if (spec.factors_size() > doe::kMaxFactors)
    throw InputError("spec.factors", "at most " + std::to_string(doe::kMaxFactors) + " factors");
  std::set<std::string> seen;
  for (int i = 0; i < spec.factors_size(); ++i) {
    const auto& f = spec.factors(i);
    const std::string where = "spec." + idx("factors", i);
    const lab::ParameterInfo info = lab::require_parameter(model, f.path(), where + ".path");
    if (spec.fixed().count(f.path()))
      throw InputError(where + ".path", "'" + f.path() + "' is also in spec.fixed");
    if (!seen.insert(f.path()).second)
      throw InputError(where + ".path", "'" + f.path() + "' is a factor twice");
    check_factor_bounds(f, info, where);
    lab::with_parameters(
        model, {{f.path(), f.low(), where + ".low"}, {f.path(), f.high(), where + ".high"}});
    for (const auto& [name, instance] : instances)
      if (!lab::has_parameter(instance, f.path()))
        throw InputError(where + ".path", "'" + f.path() + "' is not a parameter of test '" + name +
                                              "' (its own wall_law lacks it)");
    plan_tied(spec, f, model, instances, where, seen);
    plan.factors.push_back(
        {f.path(),
         doe::Factor{f.name().empty() ? f.path() : f.name(), f.low(), f.high(),
                     f.scale() == v1::Factor::LOG ? doe::Scale::kLog : doe::Scale::kLinear}});
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
  const std::set<std::string> tests(plan.tests.begin(), plan.tests.end());
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

constexpr std::string_view kSettingsPrefix = "settings.";

/// Whether a test instance has the fidelity axis's setting.
bool has_setting(const v1::LabTest& t, const std::string& name) {
  const auto& info = lab::find_lab_info(t.test());
  return std::any_of(info.settings.begin(), info.settings.end(),
                     [&](const contact::ParamDoc& d) { return d.name == name; });
}

/// A fidelity level of a test setting: every instance that has the setting takes the value,
/// checked against the setting's range and the instance's size limit.
void check_setting_level(const v1::CampaignSpec& spec, const std::string& name, double value,
                         const std::string& where) {
  int users = 0;
  for (int i = 0; i < spec.tests_size(); ++i) {
    const auto& t = spec.tests(i);
    if (!has_setting(t, name)) continue;
    ++users;
    lab::Settings settings = rpc::to_settings(t.settings());
    settings[name] = value;
    try {
      lab::admit_lab_test(t.test(), instance_model(spec, t, where), settings);
    } catch (const InputError& e) {
      throw InputError(where, "test '" + instance_name(t) + "': " + e.where() + ": " + e.message());
    }
  }
  if (users == 0)
    throw InputError("spec.fidelity.path",
                     "no test of the campaign has the setting '" + name + "'");
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

/// The fidelity axis: a test setting or a material parameter no factor, tie or fixed value sets,
/// two distinct finite levels inside its range, the high rows, and the jobs they add.
void plan_fidelity(const v1::CampaignSpec& spec, const lab::MaterialModel& model,
                   CampaignPlan& plan) {
  if (!spec.has_fidelity()) return;
  const auto& f = spec.fidelity();
  if (f.path().empty()) throw InputError("spec.fidelity.path", "missing");
  if (!std::isfinite(f.low())) throw InputError("spec.fidelity.low", "must be finite");
  if (!std::isfinite(f.high())) throw InputError("spec.fidelity.high", "must be finite");
  if (f.low() == f.high())
    throw InputError("spec.fidelity.high", "must differ from low (" + fmt(f.low()) + ")");
  if (f.path().starts_with(kSettingsPrefix)) {
    const std::string name = f.path().substr(kSettingsPrefix.size());
    check_setting_level(spec, name, f.low(), "spec.fidelity.low");
    check_setting_level(spec, name, f.high(), "spec.fidelity.high");
  } else {
    lab::require_parameter(model, f.path(), "spec.fidelity.path");
    for (const auto& factor : spec.factors()) {
      const bool tied =
          std::find(factor.tied().begin(), factor.tied().end(), f.path()) != factor.tied().end();
      if (factor.path() == f.path() || tied)
        throw InputError("spec.fidelity.path", "'" + f.path() + "' is also a factor or a tie");
    }
    if (spec.fixed().count(f.path()))
      throw InputError("spec.fidelity.path", "'" + f.path() + "' is also in spec.fixed");
    lab::with_parameters(model, {{f.path(), f.low(), "spec.fidelity.low"},
                                 {f.path(), f.high(), "spec.fidelity.high"}});
  }
  plan.fidelity = FidelityPlan{f.path(), f.low(), f.high(), planned_high_rows(f, plan.design)};
  const long jobs = static_cast<long>(plan.design.runs() + plan.fidelity->high_rows.size()) *
                    std::max(1, spec.tests_size());
  if (jobs > kMaxCampaignJobs)
    throw InputError("spec.fidelity.high_rows",
                     std::to_string(jobs) + " jobs with the high rows; at most " +
                         std::to_string(kMaxCampaignJobs) + " per campaign");
}

}  // namespace

v1::CampaignSpec at_fidelity(const v1::CampaignSpec& spec, const CampaignPlan& plan, bool high) {
  if (!plan.fidelity) return spec;
  const FidelityPlan& f = *plan.fidelity;
  const double value = high ? f.high : f.low;
  v1::CampaignSpec out = spec;
  if (!f.path.starts_with(kSettingsPrefix)) {
    (*out.mutable_fixed())[f.path] = value;
    return out;
  }
  const std::string name = f.path.substr(kSettingsPrefix.size());
  for (auto& t : *out.mutable_tests())
    if (has_setting(t, name)) (*t.mutable_settings())[name] = value;
  return out;
}

namespace {

/// The bytes the campaign's jobs would store at most kMaxCampaignPayloadBytes: the material is
/// copied into every job, so its size times the jobs, checked before any job is built.
void check_campaign_bytes(const v1::CampaignSpec& spec, const CampaignPlan& plan) {
  const std::size_t rows =
      std::size_t(plan.design.runs()) + (plan.fidelity ? plan.fidelity->high_rows.size() : 0);
  const std::size_t jobs = rows * std::size_t(std::max(1, spec.tests_size()));
  const std::size_t material = to_json(spec.material()).size();
  if (jobs * material > kMaxCampaignPayloadBytes)
    throw InputError("spec.material",
                     std::to_string(material) + " bytes copied into each of " +
                         std::to_string(jobs) + " jobs, more than the " +
                         std::to_string(kMaxCampaignPayloadBytes / kMiB) +
                         " MiB a campaign may store (fewer size classes or fewer jobs)");
}

}  // namespace

CampaignPlan plan_campaign(const v1::CampaignSpec& spec, std::vector<NewJob>& jobs) {
  CampaignPlan plan;
  check_fields(spec, "spec");
  if (spec.name().empty()) throw InputError("spec.name", "missing");
  check_printable(spec.name(), "spec.name");
  if (!spec.has_material()) throw InputError("spec.material", "missing");
  lab::MaterialModel model = rpc::to_material_model(spec.material(), "spec.material");
  Instances instances = plan_tests(spec, plan);
  apply_fixed(spec, model, instances);
  plan_factors(spec, model, instances, plan);
  plan_design(spec, plan);
  plan_targets(spec, plan);
  plan_fidelity(spec, model, plan);
  check_campaign_bytes(spec, plan);
  // Checked at submission so that a bad calibration or diagnosis block is refused before
  // anything runs.
  (void)calibration_options(spec.calibration(), "spec.calibration");
  (void)diagnose_options(spec.diagnose(), "spec.diagnose");
  jobs = design_jobs(at_fidelity(spec, plan, false), plan, plan.factors,
                     std::string(job_kind::kDesign), 0);
  if (plan.fidelity) {
    const auto high = design_jobs(at_fidelity(spec, plan, true), plan, plan.factors,
                                  std::string(job_kind::kHighDesign), 0, &plan.fidelity->high_rows);
    jobs.insert(jobs.end(), high.begin(), high.end());
  }
  return plan;
}

std::vector<NewJob> design_jobs(const v1::CampaignSpec& spec, const CampaignPlan& plan,
                                const std::vector<PlannedFactor>& box, const std::string& kind,
                                int stage_offset, const std::vector<int>* rows) {
  std::vector<NewJob> jobs;
  const auto& design = plan.design;
  const bool pinned = spec.design().simulation_seeds() == v1::Design::PINNED;
  for (int r = 0; r < design.runs(); ++r) {
    if (rows && std::find(rows->begin(), rows->end(), r + 1) == rows->end()) continue;
    std::map<std::string, double> parameters;
    for (std::size_t f = 0; f < box.size(); ++f)
      parameters[box[f].path] = box[f].factor.to_natural(design.coded(r, Eigen::Index(f)));
    for (int i = 0; i < spec.tests_size(); ++i) {
      const auto& t = spec.tests(i);
      const std::uint64_t seed = design_seed(t, spec.design(), design, r) +
                                 (pinned ? 0 : static_cast<std::uint64_t>(stage_offset));
      const v1::JobSpec job = instance_job(spec, t, spec.material(), parameters, seed);
      admit_job(job, "spec." + idx("tests", i), r + 1);
      jobs.push_back(new_job(r + 1, design.run_order[std::size_t(r)], instance_name(t), kind, job));
    }
  }
  return jobs;
}

std::vector<NewJob> jobs_at(const v1::CampaignSpec& spec, const v1::Material& material,
                            const std::map<std::string, double>& parameters, int std_order,
                            const std::string& kind, std::uint64_t seed_offset) {
  std::vector<NewJob> jobs;
  int order = 0;
  for (const auto& t : spec.tests())
    jobs.push_back(
        new_job(std_order, ++order, instance_name(t), kind,
                instance_job(spec, t, material, parameters, base_seed(t) + seed_offset)));
  return jobs;
}

std::vector<std::string> factor_legend(const CampaignPlan& plan) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < plan.factors.size(); ++i) {
    const auto& f = plan.factors[i];
    std::string s = std::string(1, doe::factor_letter(int(i))) + "=" + f.factor.name;
    if (f.factor.name != f.path) s += " (" + f.path + ")";
    s += " [" + fmt(f.factor.low) + ", " + fmt(f.factor.high) + "]";
    if (f.factor.scale == doe::Scale::kLog) s += " log";
    out.push_back(s);
  }
  return out;
}

v1::DesignSummary design_summary(const CampaignPlan& plan, int jobs) {
  v1::DesignSummary s;
  const auto a = doe::analyse_aliasing(plan.design.coded);
  s.set_description(plan.design.description);
  s.set_runs(plan.design.runs());
  s.set_jobs(jobs);
  s.set_resolution(doe::resolution_name(a.resolution));
  s.set_generators(doe::generators_text(plan.design));
  for (const auto& w : a.defining_relation) s.add_defining_relation(doe::word_name(w));
  for (const auto& c : a.two_factor_chains) s.add_two_factor_alias_chains(doe::chain_name(c));
  for (const auto& c : a.main_effect_chains) s.add_main_effect_alias_chains(doe::chain_name(c));
  for (const auto w : a.clear_two_factor) s.add_clear_two_factor_interactions(doe::word_name(w));
  for (const auto& l : factor_legend(plan)) s.add_factor_letters(l);
  return s;
}

v1::DesignReply design_reply(const CampaignPlan& plan, int jobs) {
  v1::DesignReply r;
  *r.mutable_summary() = design_summary(plan, jobs);
  for (const auto& f : plan.factors) r.add_factors(f.path);
  const auto& d = plan.design;
  for (int row : d.rows_in_run_order()) {
    auto* run = r.add_runs();
    run->set_std_order(row + 1);
    run->set_run_order(d.run_order[std::size_t(row)]);
    run->set_point_type(doe::to_string(d.point_type[std::size_t(row)]));
    run->set_replicate(d.replicate[std::size_t(row)]);
    for (int c = 0; c < d.factors(); ++c) {
      run->add_coded(d.coded(row, c));
      run->add_natural(plan.factors[std::size_t(c)].factor.to_natural(d.coded(row, c)));
    }
  }
  return r;
}

v1::Progress progress_message(const CampaignRow& row, const Counts& c, double now) {
  v1::Progress p;
  p.set_queued(c.queued);
  p.set_leased(c.leased);
  p.set_done(c.done);
  p.set_failed(c.failed);
  p.set_cancelled(c.cancelled);
  p.set_reused(c.reused);
  p.set_total(c.total());
  const double end = row.finished > 0 ? row.finished : now;
  const double elapsed = std::max(0.0, end - row.created);
  p.set_elapsed_seconds(elapsed);
  const auto finished = c.done + c.failed;
  const auto remaining = c.queued + c.leased;
  p.set_eta_seconds(remaining == 0 ? 0.0
                    : finished > 0 ? elapsed / double(finished) * double(remaining)
                                   : -1.0);
  return p;
}

v1::Campaign campaign_message(const CampaignRow& row, const Counts& counts, double now,
                              bool with_spec) {
  v1::Campaign c;
  c.set_id(row.id);
  c.set_name(row.name);
  c.set_state(row.state == "running"     ? v1::RUNNING
              : row.state == "done"      ? v1::DONE
              : row.state == "cancelled" ? v1::CANCELLED
                                         : v1::CAMPAIGN_STATE_UNSPECIFIED);
  *c.mutable_progress() = progress_message(row, counts, now);
  const auto t = static_cast<std::time_t>(row.created);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  c.set_created_at(buf);
  if (with_spec) *c.mutable_spec() = spec_from_json(row.spec_json);
  return c;
}

v1::JobResult job_message(const JobRow& job) {
  v1::JobResult r;
  r.set_job_id(job.id);
  r.set_std_order(job.std_order);
  r.set_test(job.test);
  r.set_kind(job.kind);
  r.set_state(job.state);
  r.set_attempt(job.attempt);
  if (job.metrics_json)
    for (const auto& [k, v] : metrics_from_json(*job.metrics_json)) (*r.mutable_metrics())[k] = v;
  r.set_error(job.error);
  r.set_worker(job.worker);
  r.set_wall_seconds(job.wall_seconds);
  for (const auto& [k, v] : flags_from_json(job.flags_json)) (*r.mutable_flags())[k] = v;
  *r.mutable_cost() = cost_from_json(job.cost_json);
  r.set_run_key(job.run_key.key);
  r.set_run_protocol(job.run_key.protocol);
  r.set_reused_from(job.reused_from);
  r.set_reused_journal(job.reused_journal);
  return r;
}

std::string export_campaign(const CampaignRow& row, const CampaignPlan& plan,
                            const std::vector<JobRow>& jobs,
                            const std::vector<v1::CalibrationRound>& rounds,
                            const std::string& format,
                            const std::map<std::int64_t, std::string>* series) {
  const Eigen::MatrixXd y = response_matrix(plan, jobs);
  const auto& d = plan.design;
  if (format == "csv") {
    std::ostringstream s;
    s << std::setprecision(10) << "run,std_order,point_type,replicate";
    for (const auto& f : plan.factors) s << "," << f.factor.name;
    for (const auto& r : plan.responses) s << "," << r;
    s << "\n";
    for (int r : d.rows_in_run_order()) {
      s << d.run_order[std::size_t(r)] << "," << r + 1 << ","
        << doe::to_string(d.point_type[std::size_t(r)]) << "," << d.replicate[std::size_t(r)];
      for (std::size_t f = 0; f < plan.factors.size(); ++f)
        s << "," << plan.factors[f].factor.to_natural(d.coded(r, Eigen::Index(f)));
      for (Eigen::Index c = 0; c < y.cols(); ++c) {
        s << ",";
        if (std::isfinite(y(r, c)))
          s << y(r, c);
        else
          s << "NA";
      }
      s << "\n";
    }
    return s.str();
  }
  nlohmann::json j;
  j["id"] = row.id;
  j["name"] = row.name;
  j["state"] = row.state;
  j["spec"] = column_document(row.spec_json);
  j["design"] = nlohmann::json::parse(plan_to_json(plan));
  j["reused"] =
      std::count_if(jobs.begin(), jobs.end(), [](const JobRow& job) { return job.reused(); });
  for (const auto& job : jobs) {
    nlohmann::json o = {{"job_id", job.id},
                        {"std_order", job.std_order},
                        {"test", job.test},
                        {"kind", job.kind},
                        {"state", job.state},
                        {"attempt", job.attempt},
                        {"error", job.error},
                        {"worker", job.worker},
                        {"wall_seconds", job.wall_seconds},
                        {"run_key", job.run_key.key},
                        {"reused_from", job.reused_from},
                        {"reused_journal", job.reused_journal}};
    if (job.metrics_json) {
      o["metrics"] = column_document(*job.metrics_json);
      o["flags"] = column_document(job.flags_json);
      o["cost"] = column_document(job.cost_json);
    }
    if (series) {
      const auto it = series->find(job.id);
      o["series"] = it == series->end() ? nlohmann::json::object() : column_document(it->second);
    }
    j["jobs"].push_back(o);
  }
  j["calibration_rounds"] = nlohmann::json::array();
  for (const auto& r : rounds) j["calibration_rounds"].push_back(nlohmann::json::parse(to_json(r)));
  return j.dump(2);
}

}  // namespace demcal::server
