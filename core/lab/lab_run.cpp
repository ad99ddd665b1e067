#include "core/lab/lab_run.hpp"

#include <chrono>

#include "core/common/error.hpp"
#include "core/lab/run_cancelled.hpp"
#include "core/model/lab_tests.hpp"

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

using LabRunner = LabOutput (*)(const MaterialModel&, const Settings&, const RunOptions&);

/// The runner of a catalogued test: the registry (core/model/lab_tests.hpp) lists each test's
/// catalogue entry and runner together, so every entry has one.
LabRunner runner_of(const std::string& name) {
  static const std::map<std::string, LabRunner> runners = std::apply(
      [](auto... test) {
        return std::map<std::string, LabRunner>{
            {decltype(test)::info().name, &decltype(test)::run}...};
      },
      LabTests{});
  return runners.at(name);
}

}  // namespace

void poll_progress() {
  if (current_progress.report && *current_progress.report)
    (*current_progress.report)(current_progress.last);
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
  admit_lab_test(name, material, settings);
  const auto started = std::chrono::steady_clock::now();
  RunOptions run = options;
  if (options.progress)
    run.progress = [&options](double fraction) {
      current_progress.last = fraction;
      options.progress(fraction);
    };
  const ProgressScope scope(&options.progress);
  LabOutput out = runner_of(name)(material, settings, run);
  out.cost.wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (out.resumed_from != options.resume.stage)
    throw InputError("checkpoint", "stage '" + options.resume.stage + "' is not one the " + name +
                                       " test goes on from");
  for (const auto& m : info.metrics)
    if (!out.metrics.count(m.name))
      throw std::logic_error("lab test '" + name + "' did not produce its metric '" + m.name + "'");
  for (const auto& [metric, value] : out.metrics)
    if (!reports_metric(info, metric))
      throw std::logic_error("lab test '" + name + "' reported '" + metric +
                             "', which its catalogue entry neither lists nor also reports");
  return out;
}

}  // namespace demcal::lab
