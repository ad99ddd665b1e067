#pragma once
// Where the time of a lab test goes: its time step and what bounds it, and per phase the steps,
// simulated and wall time, and whether the phase reached its target. A metric computed from a
// phase that did not reach its target carries a flag naming that phase (LabOutput::flags).
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/bytes.hpp"

namespace demcal::sim {
class World;
}

namespace demcal::lab {

struct PhaseCost {
  std::string name;    ///< e.g. "settle", "load 1", "unload 2"
  std::string target;  ///< what the phase had to reach, in words with its number
  std::int64_t steps = 0;
  double simulated_time = 0.0;  ///< (s)
  double wall_seconds = 0.0;
  bool reached = true;  ///< false: the phase ended at its time limit short of its target
};

struct RunCost {
  double time_step = 0.0;           ///< (s, simulated) at the end of the run
  double critical_time_step = 0.0;  ///< the bound at the laws' largest stiffness (s)
  std::string time_step_limit;      ///< which bound sets it, and the safety factor
  std::size_t particles = 0;        ///< particles (clump members counted) at the end
  std::int64_t steps = 0;           ///< all steps of the run
  double simulated_time = 0.0;      ///< (s)
  /// The whole run, building the bed included; a run resumed from a checkpoint adds the wall
  /// time of the phases its earlier attempt ran.
  double wall_seconds = 0.0;
  std::vector<PhaseCost> phases;  ///< in the order they ran

  double particle_steps_per_second() const;
  /// The wall time of the phases: of a resumed run, those its earlier attempt ran included.
  double phases_wall_seconds() const;
  /// Fills the time step, its limit and the particle count from the world a test ran on, and the
  /// steps and simulated time as the sums over the phases (a test may run phases on copies).
  void close(const sim::World& world);
};

/// Where a phase began (the world's step count and time) and its wall time so far, over the
/// attempts that ran it: what a checkpoint inside the phase keeps of its clock.
struct PhaseMark {
  std::int64_t steps0 = 0;
  double time0 = 0.0;
  double wall_seconds = 0.0;
};

/// Times one phase on a world: steps, simulated time and wall time from construction to stop().
class PhaseClock {
 public:
  /// Starts at the world's current step and time.
  explicit PhaseClock(const sim::World& world);
  /// Starts at step 0, time 0: for the phase that creates the world.
  PhaseClock();
  /// Goes on with the phase of `mark` (in an earlier attempt, for a run resumed inside it).
  explicit PhaseClock(const PhaseMark& mark);
  /// The phase's wall time so far.
  double wall_seconds() const;
  /// Where the phase began and its wall time so far.
  PhaseMark mark() const { return {steps0_, time0_, wall_seconds()}; }
  PhaseCost stop(const sim::World& world, std::string name, std::string target, bool reached) const;

 private:
  std::int64_t steps0_ = 0;
  double time0_ = 0.0;
  std::chrono::steady_clock::time_point wall0_;
};

/// A phase's cost in a checkpoint record: its fields handed to `a.field` in record order
/// (ByteWriter to save, ByteReader to restore; core/common/bytes.hpp).
template <class A, RecordOf<PhaseCost> P>
void record_fields(A& a, P& phase) {
  a.field(phase.name);
  a.field(phase.target);
  a.field(phase.steps);
  a.field(phase.simulated_time);
  a.field(phase.wall_seconds);
  a.field(phase.reached);
}

/// "15 kPa" style text of a stress in Pa, for phase targets.
std::string stress_text(double pa);

}  // namespace demcal::lab
