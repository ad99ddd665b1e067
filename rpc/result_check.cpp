#include "rpc/result_check.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <string_view>

namespace demcal::rpc {
namespace {

/// A name of a series or column: 1-64 characters of [a-z0-9_] (any case).
bool series_name_ok(const std::string& name) {
  return !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

/// The curves of a result: at most 32 series, each with a distinct valid name, 1-16 valid
/// columns and at most 2,000 full rows of finite values.
std::string series_error(const google::protobuf::RepeatedPtrField<v1::Series>& series) {
  constexpr int kMaxSeries = 32, kMaxColumns = 16, kMaxRows = 2000;
  if (series.size() > kMaxSeries) return "series: more than 32";
  std::set<std::string> names;
  for (int i = 0; i < series.size(); ++i) {
    const auto& s = series[i];
    const std::string where = "series[" + std::to_string(i) + "]";
    if (!series_name_ok(s.name())) return where + ".name: 1-64 characters of [A-Za-z0-9_]";
    if (!names.insert(s.name()).second) return where + ".name: " + s.name() + " given twice";
    if (s.columns_size() < 1 || s.columns_size() > kMaxColumns)
      return where + ".columns: 1 to 16 expected";
    for (const auto& c : s.columns())
      if (!series_name_ok(c)) return where + ".columns: 1-64 characters of [A-Za-z0-9_] each";
    if (s.values_size() % s.columns_size() != 0)
      return where + ".values: not a whole number of rows of " + std::to_string(s.columns_size());
    if (s.values_size() / s.columns_size() > kMaxRows)
      return where + ".values: more than 2000 rows";
    for (int k = 0; k < s.values_size(); ++k)
      if (!std::isfinite(s.values(k)))
        return where + ".values[" + std::to_string(k) + "]: must be finite";
  }
  return {};
}

/// result_error() of result_check.hpp: a CompleteRequest and a JournalRun carry the same fields.
template <class Result>
std::string check_result(const Result& req) {
  constexpr std::size_t kMaxText = 2000, kMaxPhases = 10000, kMaxMetrics = 10000, kMaxName = 200;
  if (static_cast<std::size_t>(req.metrics_size()) > kMaxMetrics) return "metrics: more than 10000";
  for (const auto& [metric, value] : req.metrics()) {
    if (metric.empty() || metric.size() > kMaxName)
      return "metrics: a name is empty or longer than 200 characters";
    if (!std::isfinite(value)) return "metrics." + metric + ": must be finite";
  }
  if (!std::isfinite(req.wall_seconds()) || req.wall_seconds() < 0.0)
    return "wall_seconds: must be finite and >= 0";
  for (const auto& [metric, reason] : req.flags()) {
    if (!req.metrics().contains(metric))
      return "flags." + metric + ": flags a metric the result does not report";
    if (reason.size() > kMaxText) return "flags." + metric + ": longer than 2000 characters";
  }
  if (std::string e = series_error(req.series()); !e.empty()) return e;
  const auto& c = req.cost();
  auto bad = [](double v) { return !std::isfinite(v) || v < 0.0; };
  if (bad(c.time_step()) || bad(c.simulated_time()) || bad(c.wall_seconds()) ||
      bad(c.particle_steps_per_second()) || c.steps() < 0 || c.particles() < 0)
    return "cost: numbers must be finite and >= 0";
  if (c.time_step_limit().size() > kMaxText) return "cost.time_step_limit: too long";
  if (static_cast<std::size_t>(c.phases_size()) > kMaxPhases) return "cost.phases: more than 10000";
  for (int i = 0; i < c.phases_size(); ++i) {
    const auto& p = c.phases(i);
    if (bad(p.simulated_time()) || bad(p.wall_seconds()) || p.steps() < 0)
      return "cost.phases[" + std::to_string(i) + "]: numbers must be finite and >= 0";
    if (p.name().size() > kMaxText || p.target().size() > kMaxText)
      return "cost.phases[" + std::to_string(i) + "]: text too long";
  }
  return {};
}

}  // namespace

std::string result_error(const v1::CompleteRequest& result) {
  return check_result(result);
}

std::string result_error(const v1::JournalRun& result) {
  return check_result(result);
}

std::string fail_reason(const std::string& reason) {
  if (reason.size() <= kMaxFailureReason) return reason;
  constexpr std::string_view kCut = "...";
  std::size_t cut = kMaxFailureReason - kCut.size();
  // Not inside a UTF-8 sequence: back to the start of its character.
  while (cut > 0 && (static_cast<unsigned char>(reason[cut]) & 0xC0) == 0x80) --cut;
  return reason.substr(0, cut) + std::string(kCut);
}

}  // namespace demcal::rpc
