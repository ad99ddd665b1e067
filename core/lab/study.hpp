#pragma once
// Scale and convergence studies (seed 001 §2.3 and App. B; seed 004 §3.1): the same lab test run
// at two or more coarse-graining factors (the real system kept: particle count N_i =
// N_0 (l_0 / l_i)^3 with l the length factor of the scaling law) or particle counts, each at one
// or more seeds, and how every metric moves between them.
//
// Bed size by the seeds' rule (seed 000 §2.3: "an increase of the system size has only
// negligible influence on the simulation results"; seed 001 App. B): with two or more seeds per
// value, a metric has converged from the first value (in the order given, cheapest first) whose
// mean every later value's mean matches within the combined seed-to-seed spread,
// |mean_j - mean_i| <= sqrt(sd_i^2 + sd_j^2), no run of either flagged for it. The chosen value is
// the latest of those over the test's catalogued metrics, when every one has converged.
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/lab/lab_run.hpp"

namespace demcal::lab {

enum class StudyAxis { kScaleFactor, kParticles };

/// One seed's run of a study value.
struct StudyReplicate {
  std::uint64_t seed = 0;
  std::map<std::string, double> metrics;
  std::map<std::string, std::string> flags;  ///< as LabOutput::flags
  double wall_seconds = 0.0;
};

struct StudyRun {
  double value = 0.0;  ///< scale factor or particle count
  double particles = 0.0;
  std::vector<StudyReplicate> replicates;  ///< one per seed
  std::map<std::string, double> metrics;   ///< mean over the seeds
  std::map<std::string, double> spread;    ///< sample standard deviation over the seeds (0: one)
  std::set<std::string> flagged;           ///< metrics flagged in some seed's run
};

struct StudyResult {
  StudyAxis axis = StudyAxis::kParticles;
  contact::ScalingLaw scaling = contact::ScalingLaw::kNone;  ///< the material's
  int seeds = 1;
  std::vector<StudyRun> runs;
  /// Per metric: relative change of each run's mean against the previous one,
  /// (m_i - m_{i-1}) / |m_{i-1}|, and the largest relative deviation from the last run.
  std::map<std::string, std::vector<double>> relative_change;
  std::map<std::string, double> max_deviation_from_last;
  /// With two or more seeds, per catalogued metric: the value it has converged from (header
  /// comment), empty if none has.
  std::map<std::string, std::optional<double>> converged_from;
  /// The value every catalogued metric has converged from, if there is one.
  std::optional<double> chosen;
};

/// Where a study keeps its finished runs as they finish, so that an interrupted study goes on
/// where it stopped: `find` gives the replicate of a value and seed run before (none: run it),
/// `add` is told each replicate the study has just run. Both may be empty.
struct StudyJournal {
  std::function<std::optional<StudyReplicate>(double value, std::uint64_t seed)> find;
  std::function<void(double value, const StudyReplicate& replicate)> add;
};

/// The mean of `values` and their sample standard deviation (0 for a single value); `values` must
/// not be empty.
struct SampleMoments {
  double mean = 0.0;
  double sd = 0.0;
};
SampleMoments sample_moments(const std::vector<double>& values);

/// The most seeds a study runs per value.
inline constexpr int kMaxStudySeeds = 10;

/// Runs `test` at every value with seeds options.seed, options.seed + 1, ... (`seeds` of them,
/// 1 to kMaxStudySeeds), taking the replicates `journal` already holds instead of running them
/// again. For kScaleFactor the material's scaling law must not be kNone.
StudyResult run_study(const std::string& test, const MaterialModel& material,
                      const Settings& settings, const RunOptions& options, StudyAxis axis,
                      const std::vector<double>& values, int seeds = 1,
                      const StudyJournal& journal = {});

/// The convergence rule of the header comment for one metric of finished runs: the index of the
/// first run from which every later run agrees with it; empty if none does (one run never does).
std::optional<std::size_t> converged_index(const std::vector<StudyRun>& runs,
                                           const std::string& metric);

}  // namespace demcal::lab
