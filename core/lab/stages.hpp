#pragma once
// The checkpoint stages of a lab test run (docs/worker.md, "Checkpoints"). A test names its
// stages in the order it reaches them; at each it offers a record of its whole state there: the
// world's state, the output so far and the runner's own fields (what its phases measured, the
// geometry it built). A run resumed from a stage restores them instead of simulating up to it
// and goes on with the stage after, so that its metrics are bitwise those of a run that was
// never interrupted (the steps are deterministic for a thread count). A value the test derives
// from the world once and uses later belongs in the record: the time step adapts as the run
// goes, so a servo's hold time or a frame's steps derived again at a later stage would differ.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/bytes.hpp"
#include "core/lab/lab_run.hpp"
#include "core/sim/world.hpp"

namespace demcal::lab {

/// A series in a record: its columns and rows.
template <class A, RecordOf<Series> S>
void record_fields(A& a, S& series) {
  a.field(series.columns);
  a.field(series.rows);
}

/// What a lab output has so far, in record order. The run's cost is its phases (the rest is
/// filled at the run's end) and `resumed_from` is the resuming run's own.
template <class A, RecordOf<LabOutput> O>
void record_fields(A& a, O& out) {
  a.field(out.metrics);
  a.field(out.series);
  a.field(out.snapshots);
  a.field(out.notes);
  a.field(out.flags);
  a.field(out.cost.phases);
}

/// `Fields` is called with a ByteWriter or a ByteReader and hands the runner's own state to its
/// `field` (e.g. `[&](auto& a) { a.field(bed); a.field(cycles); }`).
template <class Fields>
class Stages {
 public:
  Stages(const RunOptions& options, std::vector<std::string> names, LabOutput& out, Fields fields)
      : options_(options), names_(std::move(names)), out_(out), fields_(std::move(fields)) {}

  const std::string& name(std::size_t k) const { return names_.at(k); }
  /// The run goes on from a checkpoint: resume() then needs the world the test sets up.
  bool resuming() const { return !options_.resume.stage.empty(); }
  std::size_t size() const { return names_.size(); }

  /// The index of the first stage still to reach: 0 for a run from the start. A run resumed
  /// from one of the stages gets its record restored into `world` (made as the test makes it:
  /// its laws, its threads), the output and the fields, and the index after that stage; a
  /// stage that is not one of them is refused naming `checkpoint`.
  std::size_t resume(sim::World& world) {
    if (!resuming()) return 0;
    const std::string& stage = options_.resume.stage;
    const auto at = std::find(names_.begin(), names_.end(), stage);
    if (at == names_.end())
      throw InputError("checkpoint", "stage '" + stage + "' is not one this test goes on from");
    ByteReader in(options_.resume.state, "checkpoint");
    if (const auto format = in.get<std::uint32_t>(); format != kFormat)
      throw InputError("checkpoint", "a record of format " + std::to_string(format) +
                                         ", this build reads format " + std::to_string(kFormat));
    std::string state;
    in.get(state);
    world.restore_state(state);
    in.field(out_);
    fields_(in);
    in.expect_end();
    // The run's wall time counts the phases the earlier attempt ran (run_lab_test adds this
    // attempt's), so that its particle-steps per second stay those of the steps it counts.
    out_.cost.wall_seconds = out_.cost.phases_wall_seconds();
    out_.resumed_from = stage;
    out_.notes.push_back("went on from the checkpoint '" + stage +
                         "': the phases up to it ran in an earlier attempt (their costs are its)");
    return static_cast<std::size_t>(at - names_.begin()) + 1;
  }

  /// Stage `k` is reached with `world`: offers its checkpoint (the record is made only when
  /// the receiver keeps it).
  void reached(std::size_t k, const sim::World& world) const {
    if (!options_.checkpoint) return;
    options_.checkpoint(names_.at(k), [&] {
      ByteWriter record;
      record.put(kFormat);
      record.put(world.save_state());
      record.field(out_);
      fields_(record);
      return record.take();
    });
  }

 private:
  /// The record's layout: the world's state, the output, the runner's fields (1: the bed
  /// alone, without this number).
  static constexpr std::uint32_t kFormat = 2;
  const RunOptions& options_;
  std::vector<std::string> names_;
  LabOutput& out_;
  Fields fields_;
};

}  // namespace demcal::lab
