#pragma once
// Running a virtual lab test: a scenario that builds its own bed from a material model and
// settings, runs named phases and returns named metrics, time series and optional VTK snapshots.
// A blow-up is a SimulationFailure with its reason, never numbers.
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/lab/cost.hpp"
#include "core/model/catalog.hpp"
#include "core/model/material.hpp"

namespace demcal::lab {

class StageCache;

struct Series {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
};

/// At most `max_rows` rows of `series`, evenly spread over it, the first and the last kept (what
/// a worker sends with its result; `demcal lab run` writes the full series).
Series thinned(const Series& series, std::size_t max_rows);

/// A point a run can go on from (docs/worker.md, "Checkpoints"): the stage it had reached and
/// the record of its state there. A run resumed from it gives bitwise the metrics of a run that
/// was never interrupted, on the same number of threads.
struct Checkpoint {
  std::string stage;  ///< e.g. "piston bed"; empty: none
  std::string state;  ///< the stage's record (the world's state and what the test keeps of it)
};

/// Where a run stood when it offered a checkpoint: the simulated time and steps of the world the
/// checkpoint holds, since the run's start (a resumed run's include the earlier attempts'; a
/// test that runs a phase on a copy of a state reports the copy's, which count the steps that
/// made that state).
struct CheckpointClock {
  double simulated_seconds = 0.0;
  std::int64_t steps = 0;
};

struct LabOutput {
  std::map<std::string, double> metrics;  ///< by the names of the catalogue
  std::map<std::string, Series> series;
  std::vector<std::string> snapshots;  ///< VTK files written
  std::vector<std::string> notes;      ///< plain statements about the result
  RunCost cost;                        ///< time step, steps, wall time, phases
  /// Metrics that cannot be trusted, with the reason: a phase they are computed from did not
  /// reach its target. A flagged metric is reported, never silently used.
  std::map<std::string, std::string> flags;
  /// The checkpoint stage the run went on from (empty: it ran from the start).
  std::string resumed_from;

  /// Records a phase; if it did not reach its target, flags `metrics` with its name and target.
  void add_phase(const PhaseCost& phase, const std::vector<std::string>& metrics);
};

struct RunOptions {
  int threads = 1;
  std::uint64_t seed = 1;
  std::string snapshot_dir;                       ///< empty: no VTK
  std::function<void(double fraction)> progress;  ///< optional, 0..1
  /// Offered a checkpoint at each stage a test can go on from, with the run's clock there and
  /// the maker of its record: the receiver calls it only for a checkpoint it keeps (a worker,
  /// every few minutes).
  std::function<void(const std::string& stage, const CheckpointClock& clock,
                     const std::function<std::string()>& record)>
      checkpoint;
  /// Go on from this checkpoint instead of simulating up to its stage (empty stage: start
  /// afresh). run_lab_test refuses one whose stage the test never reached.
  Checkpoint resume;
  /// Where runs keep the stages other runs can start from (core/lab/stage_cache.hpp); none:
  /// every run computes its own.
  std::shared_ptr<const StageCache> stage_cache;
};

/// Runs a test by name: admits its input (admit_lab_test), runs, and checks that every
/// catalogued metric was produced and that every metric it reports is one the catalogue names
/// (the coordinator refuses a result with another).
LabOutput run_lab_test(const std::string& name, const MaterialModel& material,
                       const Settings& settings, const RunOptions& options);

}  // namespace demcal::lab
