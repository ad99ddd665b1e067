#include "core/lab/lab_test.hpp"

#include <chrono>

#include "core/common/error.hpp"
#include "core/lab/compaction.hpp"
#include "core/lab/confined_compression.hpp"
#include "core/lab/hopper.hpp"
#include "core/lab/packing.hpp"
#include "core/lab/rotating_drum.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/lab/shear_cell.hpp"
#include "core/lab/tensile.hpp"
#include "core/lab/wall_friction.hpp"

namespace demcal::lab {

namespace {

/// The progress callback of the lab test running on this thread and its last fraction.
struct ProgressHook {
  const std::function<void(double)>* report = nullptr;
  double last = 0.0;
};
thread_local ProgressHook current_progress;

/// Installs a run's callback for poll_progress() and restores the previous one (a test run
/// inside another, as a study does) when the run ends or unwinds.
class ProgressScope {
 public:
  explicit ProgressScope(const std::function<void(double)>* report) : saved_(current_progress) {
    current_progress = {report, 0.0};
  }
  ~ProgressScope() { current_progress = saved_; }
  ProgressScope(const ProgressScope&) = delete;
  ProgressScope& operator=(const ProgressScope&) = delete;

 private:
  ProgressHook saved_;
};

}  // namespace

void poll_progress() {
  if (current_progress.report && *current_progress.report)
    (*current_progress.report)(current_progress.last);
}

const std::map<std::string, LabRunner>& lab_runners() {
  // One entry per lab test; its catalogue entry (name, metrics, settings) is in catalog.cpp.
  static const std::map<std::string, LabRunner> runners{
      {"packing", run_packing},       {"confined_compression", run_confined_compression},
      {"tensile", run_tensile},       {"wall_friction", run_wall_friction},
      {"shear_cell", run_shear_cell}, {"rotating_drum", run_rotating_drum},
      {"hopper", run_hopper},         {"compaction", run_compaction},
  };
  return runners;
}

LabRunner find_lab_runner(const std::string& name) {
  const auto& runners = lab_runners();
  if (const auto it = runners.find(name); it != runners.end()) return it->second;
  find_lab_info(name);  // throws with the known names
  throw InputError("test", "lab test '" + name + "' is catalogued but has no runner");
}

Series thinned(const Series& series, std::size_t max_rows) {
  const std::size_t n = series.rows.size();
  if (n <= max_rows) return series;
  Series out{series.columns, {}};
  if (max_rows == 0) return out;
  out.rows.reserve(max_rows);
  if (max_rows == 1) {
    out.rows.push_back(series.rows.back());
    return out;
  }
  // Row k of the result is row round(k (n - 1) / (max_rows - 1)): strictly increasing because
  // n > max_rows, so no row is taken twice.
  for (std::size_t k = 0; k < max_rows; ++k)
    out.rows.push_back(series.rows[(k * (n - 1) + (max_rows - 1) / 2) / (max_rows - 1)]);
  return out;
}

void LabOutput::add_phase(const PhaseCost& phase, const std::vector<std::string>& depending) {
  cost.phases.push_back(phase);
  if (phase.reached) return;
  const std::string why = "phase '" + phase.name + "' did not reach " + phase.target;
  for (const auto& m : depending) {
    std::string& flag = flags[m];
    flag += (flag.empty() ? "" : "; ") + why;
  }
}

LabOutput run_lab_test(const std::string& name, const MaterialModel& material,
                       const Settings& settings, const RunOptions& options) {
  const LabTestInfo& info = find_lab_info(name);
  validate_settings(info, settings, "settings");
  const auto started = std::chrono::steady_clock::now();
  RunOptions run = options;
  if (options.progress)
    run.progress = [&options](double fraction) {
      current_progress.last = fraction;
      options.progress(fraction);
    };
  const ProgressScope scope(&options.progress);
  LabOutput out = find_lab_runner(name)(material, settings, run);
  out.cost.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  for (const auto& m : info.metrics)
    if (!out.metrics.count(m.name))
      throw std::logic_error("lab test '" + name + "' did not produce its metric '" + m.name + "'");
  return out;
}

}  // namespace demcal::lab
