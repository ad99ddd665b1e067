// The plan as stored in campaigns.design_json (plan.hpp), and a plan stored before it held the
// whole campaign.
#include <nlohmann/json.hpp>

#include "core/model/campaign_model.hpp"
#include "rpc/material_convert.hpp"
#include "server/convert.hpp"
#include "server/plan.hpp"
#include "server/plan_input.hpp"
#include "server/stored_columns.hpp"

namespace demcal::server {
namespace {

using Json = nlohmann::json;

/// The form of the stored plan: 2 holds the whole validated campaign; a plan without one holds
/// the design, responses, targets and fidelity axis only.
constexpr int kPlanForm = 2;

Json material_json(const lab::MaterialModel& material) {
  return Json::parse(to_json(rpc::to_material_message(material)));
}

lab::MaterialModel material_from(const Json& j, const std::string& where) {
  v1::Material m;
  from_json(j.dump(), m);
  return rpc::to_material_model(m, where);
}

Json instance_json(const PlannedInstance& i) {
  return {{"name", i.name},
          {"test", i.test},
          {"settings_low", i.settings_low},
          {"settings_high", i.settings_high},
          {"material", material_json(i.material)},
          {"seed", i.seed},
          {"threads", i.threads},
          {"waits_for", i.waits_for}};
}

PlannedInstance instance_from(const Json& j) {
  return {j.at("name"),
          j.at("test"),
          j.at("settings_low").get<lab::Settings>(),
          j.at("settings_high").get<lab::Settings>(),
          material_from(j.at("material"), "plan.instances.material"),
          j.at("seed").get<std::uint64_t>(),
          j.at("threads").get<int>(),
          j.at("waits_for")};
}

Json calibration_json(const CampaignPlan& p) {
  const auto& o = p.calibration;
  return {{"surrogate", o.surrogate == calib::Surrogate::kGaussianProcess ? "gp" : "polynomial"},
          {"batch", o.batch},
          {"batch_per_worker", p.batch_per_worker},
          {"rounds", o.rounds},
          {"stages", o.stages},
          {"narrow", o.narrow},
          {"max_jobs", o.max_jobs},
          {"replicates", o.replicates},
          {"model", doe::to_string(o.model)}};
}

void calibration_from(const Json& j, CampaignPlan& p) {
  auto& o = p.calibration;
  o.surrogate = j.at("surrogate") == "gp" ? calib::Surrogate::kGaussianProcess
                                          : calib::Surrogate::kPolynomial;
  o.batch = j.at("batch");
  p.batch_per_worker = j.at("batch_per_worker");
  o.rounds = j.at("rounds");
  o.stages = j.at("stages");
  o.narrow = j.at("narrow");
  o.max_jobs = j.at("max_jobs");
  o.replicates = j.value("replicates", 1);  // plans stored before replicates: one seed
  o.model = polynomial_model(j.at("model"), "plan.calibration.model");
}

Json diagnosis_json(const diagnose::Options& o) {
  return {{"candidates", o.candidates},   {"aspect_ratio_max", o.aspect_ratio_max},
          {"rolling_max", o.rolling_max}, {"sigma_g_max", o.sigma_g_max},
          {"fixed_span", o.fixed_span},   {"margin", o.margin},
          {"replicates", o.replicates},   {"nested", o.nested},
          {"rounds", o.rounds},           {"consolidation_min", o.consolidation_min}};
}

void diagnosis_from(const Json& j, diagnose::Options& o) {
  o.candidates = j.at("candidates").get<std::vector<std::string>>();
  o.aspect_ratio_max = j.at("aspect_ratio_max");
  o.rolling_max = j.at("rolling_max");
  o.sigma_g_max = j.at("sigma_g_max");
  o.fixed_span = j.at("fixed_span");
  o.margin = j.at("margin");
  o.replicates = j.at("replicates");
  // Plans stored before the option existed repeat every factorial run.
  o.nested = j.value("nested", false);
  // ... and verify up to the default number of rounds.
  o.rounds = j.value("rounds", diagnose::Options{}.rounds);
  o.consolidation_min = j.value("consolidation_min", diagnose::Options{}.consolidation_min);
}

/// The design, its responses, targets and fidelity axis: what every form of the plan holds.
void design_to(Json& j, const CampaignPlan& plan) {
  const auto& d = plan.design;
  j["description"] = d.description;
  j["factor_names"] = d.factor_names;
  for (int r = 0; r < d.runs(); ++r) {
    std::vector<double> row;
    for (int c = 0; c < d.factors(); ++c) row.push_back(d.coded(r, c));
    j["coded"].push_back(row);
    j["point_type"].push_back(static_cast<int>(d.point_type[std::size_t(r)]));
  }
  j["replicate"] = d.replicate;
  j["block"] = d.block;
  j["run_order"] = d.run_order;
  j["generators"] = d.generators;
  j["responses"] = plan.responses;
  for (const auto& t : plan.targets) {
    Json tj = {
        {"response", t.response}, {"value", t.value}, {"weight", t.weight}, {"source", t.source}};
    if (t.uncertainty) tj["uncertainty"] = *t.uncertainty;
    if (t.holdout) tj["holdout"] = true;
    j["targets"].push_back(tj);
  }
  if (plan.fidelity)
    j["fidelity"] = {{"path", plan.fidelity->path},
                     {"low", plan.fidelity->low},
                     {"high", plan.fidelity->high},
                     {"high_rows", plan.fidelity->high_rows}};
}

void design_from(const Json& j, CampaignPlan& p) {
  auto& d = p.design;
  d.description = j.at("description");
  d.factor_names = j.at("factor_names").get<std::vector<std::string>>();
  const auto& coded = j.at("coded");
  d.coded.resize(static_cast<Eigen::Index>(coded.size()),
                 static_cast<Eigen::Index>(d.factor_names.size()));
  for (std::size_t r = 0; r < coded.size(); ++r)
    for (std::size_t c = 0; c < coded[r].size(); ++c)
      d.coded(Eigen::Index(r), Eigen::Index(c)) = coded[r][c].get<double>();
  for (const auto& t : j.at("point_type"))
    d.point_type.push_back(static_cast<doe::PointType>(t.get<int>()));
  d.replicate = j.at("replicate").get<std::vector<int>>();
  d.block = j.at("block").get<std::vector<int>>();
  d.run_order = j.at("run_order").get<std::vector<int>>();
  d.generators = j.at("generators").get<std::vector<doe::Word>>();
  p.responses = j.at("responses").get<std::vector<std::string>>();
  if (j.contains("targets"))
    for (const auto& t : j.at("targets")) {
      Target tg{t.at("response"), t.at("value"), t.at("weight"), std::nullopt, t.at("source")};
      if (t.contains("uncertainty")) tg.uncertainty = t.at("uncertainty").get<double>();
      tg.holdout = t.value("holdout", false);
      p.targets.push_back(tg);
    }
  if (j.contains("fidelity")) {
    const auto& f = j.at("fidelity");
    p.fidelity = FidelityPlan{f.at("path"), f.at("low"), f.at("high"),
                              f.at("high_rows").get<std::vector<int>>()};
  }
}

/// A plan stored before the plan held the whole campaign: its design, responses, targets and
/// fidelity axis as stored, the rest read from its stored spec, the instances' settings at the
/// stored fidelity levels.
CampaignPlan earlier_plan(const Json& j, const CampaignRow& row) {
  CampaignPlan p = read_plan_input(spec_from_json(row.spec_json));
  design_from(j, p);
  if (p.fidelity) {
    const lab::CampaignFidelity f{p.fidelity->path, p.fidelity->low, p.fidelity->high};
    for (auto& i : p.instances) {
      i.settings_high = lab::at_fidelity_level(i.test, i.settings_low, f, true);
      i.settings_low = lab::at_fidelity_level(i.test, i.settings_low, f, false);
    }
  }
  return p;
}

}  // namespace

std::string plan_to_json(const CampaignPlan& plan) {
  Json j;
  j["form"] = kPlanForm;
  j["material"] = material_json(plan.material);
  j["fixed"] = plan.fixed;
  for (const auto& i : plan.instances) j["instances"].push_back(instance_json(i));
  for (const auto& f : plan.factors)
    j["factors"].push_back({{"path", f.path},
                            {"name", f.factor.name},
                            {"low", f.factor.low},
                            {"high", f.factor.high},
                            {"log", f.factor.scale == doe::Scale::kLog},
                            {"tied", f.tied}});
  j["pinned_seeds"] = plan.pinned_seeds;
  design_to(j, plan);
  j["calibration"] = calibration_json(plan);
  j["diagnosis"] = diagnosis_json(plan.diagnosis);
  return j.dump();
}

CampaignPlan stored_plan(const CampaignRow& row) {
  const Json j = Json::parse(row.design_json);
  if (!j.contains("form")) return earlier_plan(j, row);
  CampaignPlan p;
  p.material = material_from(j.at("material"), "plan.material");
  p.fixed = j.at("fixed").get<std::map<std::string, double>>();
  for (const auto& i : j.at("instances")) p.instances.push_back(instance_from(i));
  for (const auto& f : j.at("factors"))
    p.factors.push_back(
        {f.at("path"),
         doe::Factor{f.at("name"), f.at("low"), f.at("high"),
                     f.at("log").get<bool>() ? doe::Scale::kLog : doe::Scale::kLinear},
         f.at("tied").get<std::vector<std::string>>()});
  p.pinned_seeds = j.at("pinned_seeds");
  design_from(j, p);
  calibration_from(j.at("calibration"), p);
  diagnosis_from(j.at("diagnosis"), p.diagnosis);
  return p;
}

}  // namespace demcal::server
