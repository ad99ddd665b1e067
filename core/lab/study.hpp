#pragma once
// Scale and convergence studies (seed 001 §2.3 and App. B; seed 004 §3.1): the same lab test run
// at two or three coarse-graining factors (the real system kept: particle count N_i =
// N_0 (l_0 / l_i)^3 with l the length factor of the scaling law) or particle counts, and how
// every metric moves between them.
#include <string>
#include <vector>

#include "core/lab/lab_test.hpp"

namespace demcal::lab {

enum class StudyAxis { kScaleFactor, kParticles };

struct StudyRun {
  double value = 0.0;  ///< scale factor or particle count
  double particles = 0.0;
  std::map<std::string, double> metrics;
};

struct StudyResult {
  StudyAxis axis = StudyAxis::kParticles;
  std::vector<StudyRun> runs;
  /// Per metric: relative change of each run against the previous one, (m_i - m_{i-1}) / |m_{i-1}|,
  /// and the largest relative deviation from the last (finest or largest) run.
  std::map<std::string, std::vector<double>> relative_change;
  std::map<std::string, double> max_deviation_from_last;
};

/// Runs `test` once per value. For kScaleFactor the material's scaling law must not be kNone.
StudyResult run_study(const std::string& test, const MaterialModel& material,
                      const Settings& settings, const RunOptions& options, StudyAxis axis,
                      const std::vector<double>& values);

}  // namespace demcal::lab
