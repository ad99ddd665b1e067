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
  // A test sized by its geometry (the rotating drum) has no particle count: the same drum holds
  // fewer, larger particles at a larger scale factor by itself.
  bool counted = false;
  double n0 = 300.0;
  for (const auto& d : info.settings)
    if (d.name == "particles") n0 = d.fallback, counted = true;
  if (axis == StudyAxis::kParticles && !counted)
    throw InputError("study",
                     "lab test '" + test + "' has no particle count: it follows from its geometry");
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
      if (counted) s["particles"] = std::max(20.0, std::round(n0 * std::pow(l0 / l, 3)));
    } else {
      s["particles"] = v;
    }
    StudyRun run;
    run.value = v;
    run.metrics = run_lab_test(test, m, s, options).metrics;
    run.particles = counted ? s["particles"] : run.metrics.at("particles");
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
