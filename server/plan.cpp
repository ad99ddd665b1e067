#include "server/plan.hpp"

#include <nlohmann/json.hpp>

namespace demcal::server {

std::string plan_to_json(const CampaignPlan& plan) {
  nlohmann::json j;
  for (const auto& f : plan.factors)
    j["factors"].push_back({{"path", f.path},
                            {"name", f.factor.name},
                            {"low", f.factor.low},
                            {"high", f.factor.high},
                            {"log", f.factor.scale == doe::Scale::kLog}});
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
  j["tests"] = plan.tests;
  j["responses"] = plan.responses;
  for (const auto& t : plan.targets) {
    nlohmann::json tj = {
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
  return j.dump();
}

CampaignPlan plan_from_json(const std::string& text) {
  const auto j = nlohmann::json::parse(text);
  CampaignPlan p;
  for (const auto& f : j.at("factors"))
    p.factors.push_back({f.at("path"), doe::Factor{f.at("name"), f.at("low"), f.at("high"),
                                                   f.at("log").get<bool>() ? doe::Scale::kLog
                                                                           : doe::Scale::kLinear}});
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
  p.tests = j.at("tests").get<std::vector<std::string>>();
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
  return p;
}

}  // namespace demcal::server
