#include "core/lab/study.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace demcal::lab {

StudyResult run_study(const std::string& test, const MaterialModel& material,
                      const Settings& settings, const RunOptions& options, StudyAxis axis,
                      const std::vector<double>& values) {
  if (values.size() < 2) throw InputError("study", "give at least two values");
  if (axis == StudyAxis::kScaleFactor && material.scaling == contact::ScalingLaw::kNone)
    throw InputError("material.scaling.law",
                     "a scale study needs a scaling law (kottlan2018 or tiscar2019)");
  const LabTestInfo& info = find_lab_info(test);
  double n0 = 300.0;
  for (const auto& d : info.settings)
    if (d.name == "particles") n0 = d.fallback;
  if (auto it = settings.find("particles"); it != settings.end()) n0 = it->second;
  StudyResult r;
  r.axis = axis;
  const double l0 = axis == StudyAxis::kScaleFactor
                        ? contact::scale_factors(material.scaling, values[0]).length
                        : 1.0;
  for (double v : values) {
    MaterialModel m = material;
    Settings s = settings;
    if (axis == StudyAxis::kScaleFactor) {
      m.scale_factor = v;
      // The same real system: particles fewer by the cube of the length factor.
      const double l = contact::scale_factors(m.scaling, v).length;
      s["particles"] = std::max(20.0, std::round(n0 * std::pow(l0 / l, 3)));
    } else {
      s["particles"] = v;
    }
    StudyRun run;
    run.value = v;
    run.particles = s["particles"];
    run.metrics = run_lab_test(test, m, s, options).metrics;
    r.runs.push_back(std::move(run));
  }
  for (const auto& [name, last] : r.runs.back().metrics) {
    auto& ch = r.relative_change[name];
    double dev = 0.0;
    for (std::size_t i = 0; i < r.runs.size(); ++i) {
      const double m = r.runs[i].metrics.at(name);
      if (i > 0) {
        const double prev = r.runs[i - 1].metrics.at(name);
        ch.push_back(prev != 0.0 ? (m - prev) / std::abs(prev) : 0.0);
      }
      if (last != 0.0) dev = std::max(dev, std::abs(m - last) / std::abs(last));
    }
    r.max_deviation_from_last[name] = dev;
  }
  return r;
}

}  // namespace demcal::lab
