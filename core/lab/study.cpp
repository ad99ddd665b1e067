#include "core/lab/study.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace demcal::lab {
namespace {

/// Mean and sample standard deviation of every metric over the replicates, and the metrics some
/// replicate flagged.
void summarise(StudyRun& run) {
  std::vector<double> values;
  for (const auto& [name, unused] : run.replicates.front().metrics) {
    values.clear();
    for (const auto& rep : run.replicates) values.push_back(rep.metrics.at(name));
    const SampleMoments m = sample_moments(values);
    run.metrics[name] = m.mean;
    run.spread[name] = m.sd;
  }
  for (const auto& rep : run.replicates)
    for (const auto& [name, why] : rep.flags) run.flagged.insert(name);
}

void relative_changes(StudyResult& r) {
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
}

/// Whether runs a and b agree on `metric` within their combined seed-to-seed spread, neither
/// flagged for it.
bool agree(const StudyRun& a, const StudyRun& b, const std::string& metric) {
  if (a.flagged.count(metric) || b.flagged.count(metric)) return false;
  const double sa = a.spread.at(metric), sb = b.spread.at(metric);
  return std::abs(b.metrics.at(metric) - a.metrics.at(metric)) <= std::sqrt(sa * sa + sb * sb);
}

}  // namespace

SampleMoments sample_moments(const std::vector<double>& values) {
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  for (double v : values) sum += v;
  SampleMoments m;
  m.mean = sum / n;
  double squares = 0.0;
  for (double v : values) squares += (v - m.mean) * (v - m.mean);
  m.sd = n > 1.0 ? std::sqrt(squares / (n - 1.0)) : 0.0;
  return m;
}

std::optional<std::size_t> converged_index(const std::vector<StudyRun>& runs,
                                           const std::string& metric) {
  for (std::size_t i = 0; i + 1 < runs.size(); ++i) {
    bool all = true;
    for (std::size_t j = i + 1; j < runs.size() && all; ++j) all = agree(runs[i], runs[j], metric);
    if (all) return i;
  }
  return std::nullopt;
}

StudyResult run_study(const std::string& test, const MaterialModel& material,
                      const Settings& settings, const RunOptions& options, StudyAxis axis,
                      const std::vector<double>& values, int seeds, const StudyJournal& journal) {
  if (values.size() < 2) throw InputError("study", "give at least two values");
  if (seeds < 1 || seeds > kMaxStudySeeds)
    throw InputError("study.seeds", "must be in [1, " + std::to_string(kMaxStudySeeds) + "]");
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
  r.scaling = material.scaling;
  r.seeds = seeds;
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
    for (int k = 0; k < seeds; ++k) {
      RunOptions o = options;
      o.seed = options.seed + static_cast<std::uint64_t>(k);
      if (auto done = journal.find ? journal.find(v, o.seed) : std::nullopt) {
        run.replicates.push_back(std::move(*done));
        continue;
      }
      LabOutput out = run_lab_test(test, m, s, o);
      run.replicates.push_back(
          {o.seed, std::move(out.metrics), std::move(out.flags), out.cost.wall_seconds});
      if (journal.add) journal.add(v, run.replicates.back());
    }
    run.particles = counted ? s["particles"] : run.replicates.front().metrics.at("particles");
    summarise(run);
    r.runs.push_back(std::move(run));
  }
  relative_changes(r);
  if (seeds >= 2) {
    std::optional<std::size_t> chosen = 0;
    for (const auto& metric : info.metrics) {
      const auto i = converged_index(r.runs, metric.name);
      r.converged_from[metric.name] = i ? std::optional<double>(r.runs[*i].value) : std::nullopt;
      chosen = i && chosen ? std::optional<std::size_t>(std::max(*i, *chosen)) : std::nullopt;
    }
    if (chosen) r.chosen = r.runs[*chosen].value;
  }
  return r;
}

}  // namespace demcal::lab
