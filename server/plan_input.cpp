#include "server/plan_input.hpp"

#include "core/common/error.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"

namespace demcal::server {
namespace {

/// Lab seeds per diagnosis verification at most: each multiplies its verification runs.
constexpr int kMaxDiagnosisReplicates = 16;
/// Verification rounds a diagnosis candidate at most: each is one more set simulated.
constexpr int kMaxDiagnosisRounds = 10;

/// The model of a test instance: the campaign's with the instance's wall law and preparation;
/// errors in those name the instance's field.
lab::MaterialModel instance_model(const v1::CampaignSpec& spec, const v1::LabTest& t,
                                  const std::string& where) {
  try {
    return rpc::to_material_model(rpc::instance_material(spec.material(), t), "spec.material");
  } catch (const InputError& e) {
    for (const auto& [own, field] :
         {std::pair{t.has_wall_law(), "wall_law"}, {t.has_preparation(), "preparation"}}) {
      const std::string base = std::string("spec.material.") + field;
      if (own && e.where().rfind(base, 0) == 0)
        throw InputError(where + "." + field + e.where().substr(base.size()), e.message());
    }
    throw;
  }
}

PlannedInstance read_instance(const v1::CampaignSpec& spec, int i) {
  const auto& t = spec.tests(i);
  const lab::Settings settings = rpc::to_settings(t.settings());
  return {rpc::instance_name(t),
          t.test(),
          settings,
          settings,
          instance_model(spec, t, "spec.tests[" + std::to_string(i) + "]"),
          t.seed() ? t.seed() : 1,
          t.threads(),
          {}};
}

PlannedFactor read_factor(const v1::Factor& f) {
  return {f.path(),
          doe::Factor{f.name().empty() ? f.path() : f.name(), f.low(), f.high(),
                      f.scale() == v1::Factor::LOG ? doe::Scale::kLog : doe::Scale::kLinear},
          {f.tied().begin(), f.tied().end()}};
}

/// An option: `fallback` when unset (0), else `v` if lo < v <= hi.
double option(double v, double fallback, double lo, double hi, const std::string& field) {
  if (v == 0.0) return fallback;
  if (!(v > lo && v <= hi))
    throw InputError(field, "must be 0 (the default, " + message_number(fallback) + ") or in (" +
                                message_number(lo) + ", " + message_number(hi) + "]");
  return v;
}

}  // namespace

CampaignPlan read_plan_input(const v1::CampaignSpec& spec) {
  CampaignPlan plan;
  plan.material = rpc::to_material_model(spec.material(), "spec.material");
  plan.fixed = {spec.fixed().begin(), spec.fixed().end()};
  for (int i = 0; i < spec.tests_size(); ++i) plan.instances.push_back(read_instance(spec, i));
  for (const auto& f : spec.factors()) plan.factors.push_back(read_factor(f));
  plan.pinned_seeds = spec.design().simulation_seeds() == v1::Design::PINNED;
  plan.calibration = calibration_options(spec.calibration(), "spec.calibration");
  if (plan.pinned_seeds && plan.calibration.replicates > 1)
    throw InputError("spec.calibration.replicates",
                     "the design's simulation seeds are pinned, so every replicate would be the "
                     "same run: leave it at 1 or let the seeds vary");
  plan.batch_per_worker = spec.calibration().batch() == 0;
  plan.diagnosis = diagnose_options(spec.diagnose(), "spec.diagnose");
  return plan;
}

doe::ModelKind polynomial_model(const std::string& text, const std::string& where) {
  const doe::ModelKind m = doe::parse_model_kind(text, where);
  if (m != doe::ModelKind::kMain && m != doe::ModelKind::kTwoFactor)
    throw InputError(where, "the calibration fits main or 2fi models");
  return m;
}

calib::SequentialOptions calibration_options(const v1::CalibrationOptions& spec,
                                             const std::string& where) {
  calib::SequentialOptions o;
  if (spec.rounds()) o.rounds = spec.rounds();
  if (spec.stages()) o.stages = spec.stages();
  if (spec.narrow() != 0.0) o.narrow = spec.narrow();
  o.max_jobs = spec.max_jobs();
  if (spec.surrogate() == "gp")
    o.surrogate = calib::Surrogate::kGaussianProcess;
  else if (!spec.surrogate().empty() && spec.surrogate() != "polynomial")
    throw InputError(where + ".surrogate",
                     "unknown surrogate '" + spec.surrogate() + "' (polynomial or gp)");
  if (spec.batch() < 0) throw InputError(where + ".batch", "must be >= 0");
  if (spec.batch() > 0) o.batch = spec.batch();
  if (spec.replicates() != 0) o.replicates = spec.replicates();
  if (!spec.model().empty()) o.model = polynomial_model(spec.model(), where + ".model");
  o.validate(where);
  return o;
}

diagnose::Options diagnose_options(const v1::DiagnoseOptions& o, const std::string& where) {
  // Ranges: the parameter tables' (rods up to aspect ratio 20, mu_r up to 10, sigma_g up to 10),
  // a fixed parameter at most 100 x off, a margin below 1 (an error cut by 100 % cannot be).
  diagnose::Options out;
  out.candidates.assign(o.candidates().begin(), o.candidates().end());
  out.aspect_ratio_max =
      option(o.aspect_ratio_max(), out.aspect_ratio_max, 1.0, 20.0, where + ".aspect_ratio_max");
  out.rolling_max = option(o.rolling_max(), out.rolling_max, 0.0, 10.0, where + ".rolling_max");
  out.sigma_g_max =
      option(o.sigma_g_max(), out.sigma_g_max, diagnose::kSigmaGLow, 10.0, where + ".sigma_g_max");
  out.fixed_span = option(o.fixed_span(), out.fixed_span, 1.0, 100.0, where + ".fixed_span");
  out.margin = option(o.margin(), out.margin, 0.0, 0.99, where + ".margin");
  if (o.replicates() < 0 || o.replicates() > kMaxDiagnosisReplicates)
    throw InputError(where + ".replicates", "must be 0 (the default, 1) or in [1, " +
                                                std::to_string(kMaxDiagnosisReplicates) + "]");
  if (o.replicates() > 0) out.replicates = o.replicates();
  if (o.rounds() < 0 || o.rounds() > kMaxDiagnosisRounds)
    throw InputError(where + ".rounds", "must be 0 (the default, 3) or in [1, " +
                                            std::to_string(kMaxDiagnosisRounds) + "]");
  if (o.rounds() > 0) out.rounds = o.rounds();
  if (o.consolidation_min() != 0.0) {
    if (!(o.consolidation_min() >= 0.01 && o.consolidation_min() <= 0.9))
      throw InputError(where + ".consolidation_min",
                       "must be 0 (the default, 0.1) or in [0.01, 0.9]");
    out.consolidation_min = o.consolidation_min();
  }
  if (o.rows() == "nested")
    out.nested = true;
  else if (!o.rows().empty() && o.rows() != "all")
    throw InputError(where + ".rows", "unknown '" + o.rows() + "' (all or nested)");
  return out;
}

}  // namespace demcal::server
