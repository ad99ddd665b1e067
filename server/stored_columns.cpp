#include "server/stored_columns.hpp"

#include <cmath>

#include "server/convert.hpp"

namespace demcal::server {

namespace {

Eigen::VectorXd vector_of(const nlohmann::json& j) {
  Eigen::VectorXd v(Eigen::Index(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i)
    v(Eigen::Index(i)) = j[i].is_number() ? j[i].get<double>() : std::nan("");
  return v;
}

}  // namespace

nlohmann::json column_document(const std::string& column) {
  return nlohmann::json::parse(column);
}

v1::CampaignSpec spec_from_json(const std::string& spec_json) {
  v1::CampaignSpec spec;
  from_json(spec_json, spec);
  return spec;
}

std::string canonical_spec_json(const std::string& spec_json) {
  return column_document(spec_json).dump();
}

v1::JobSpec job_from_payload(const std::string& payload) {
  v1::JobSpec job;
  from_json(payload, job);
  return job;
}

std::string metrics_to_json(const std::map<std::string, double>& metrics) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [k, v] : metrics) j[k] = std::isfinite(v) ? nlohmann::json(v) : nullptr;
  return j.dump();
}

std::map<std::string, double> metrics_from_json(const std::string& metrics_json) {
  std::map<std::string, double> out;
  const auto parsed = nlohmann::json::parse(metrics_json);  // items() refers to it: keep it alive
  for (const auto& [k, v] : parsed.items()) out[k] = v.is_number() ? v.get<double>() : std::nan("");
  return out;
}

std::string flags_to_json(const google::protobuf::Map<std::string, std::string>& flags) {
  return nlohmann::json(std::map<std::string, std::string>(flags.begin(), flags.end())).dump();
}

std::map<std::string, std::string> flags_from_json(const std::string& flags_json) {
  std::map<std::string, std::string> out;
  const auto parsed = nlohmann::json::parse(flags_json);  // items() refers to it: keep it alive
  for (const auto& [metric, why] : parsed.items()) out[metric] = why.get<std::string>();
  return out;
}

v1::RunCost cost_from_json(const std::string& cost_json) {
  v1::RunCost cost;
  from_json(cost_json, cost);
  return cost;
}

std::string series_to_json(const google::protobuf::RepeatedPtrField<v1::Series>& series) {
  if (series.empty()) return {};
  nlohmann::json out = nlohmann::json::object();
  for (const auto& s : series) {
    const std::size_t width = static_cast<std::size_t>(s.columns_size());
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t at = 0; width > 0 && at < static_cast<std::size_t>(s.values_size());
         at += width)
      rows.push_back(std::vector<double>(s.values().begin() + static_cast<int>(at),
                                         s.values().begin() + static_cast<int>(at + width)));
    out[s.name()] = {{"columns", std::vector<std::string>(s.columns().begin(), s.columns().end())},
                     {"rows", std::move(rows)}};
  }
  return out.dump();
}

google::protobuf::RepeatedPtrField<v1::Series> series_from_json(const std::string& series_json) {
  google::protobuf::RepeatedPtrField<v1::Series> out;
  if (series_json.empty()) return out;
  const auto curves = nlohmann::json::parse(series_json);
  for (auto it = curves.begin(); it != curves.end(); ++it) {
    const auto& curve = it.value();
    auto* s = out.Add();
    s->set_name(it.key());
    for (const auto& column : curve.at("columns")) s->add_columns(column.get<std::string>());
    for (const auto& row : curve.at("rows"))
      for (const auto& value : row) s->add_values(value.get<double>());
  }
  return out;
}

std::string box_to_json(const std::vector<doe::Factor>& box) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& f : box) j.push_back({{"low", f.low}, {"high", f.high}});
  return j.dump();
}

std::vector<doe::Factor> box_from_json(const CampaignPlan& plan, const std::string& box_json) {
  const auto j = nlohmann::json::parse(box_json);
  std::vector<doe::Factor> box;
  for (std::size_t i = 0; i < plan.factors.size(); ++i) {
    doe::Factor f = plan.factors[i].factor;
    f.low = j.at(i).at("low").get<double>();
    f.high = j.at(i).at("high").get<double>();
    box.push_back(f);
  }
  return box;
}

std::string proposal_to_json(const Eigen::VectorXd& natural, const Eigen::VectorXd& predicted,
                             const std::vector<std::string>& metrics, int batch) {
  nlohmann::json j;
  for (Eigen::Index i = 0; i < natural.size(); ++i) j["natural"].push_back(natural(i));
  for (Eigen::Index i = 0; i < predicted.size(); ++i) j["predicted"].push_back(predicted(i));
  j["metrics"] = metrics;
  j["batch"] = batch;
  return j.dump();
}

StoredProposal proposal_from_json(const std::string& proposal_json) {
  const auto j = nlohmann::json::parse(proposal_json);
  StoredProposal p{vector_of(j.at("natural")), vector_of(j.at("predicted")), std::nullopt};
  if (j.contains("batch")) p.batch = j.at("batch").get<int>();
  return p;
}

}  // namespace demcal::server
