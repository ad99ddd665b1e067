#pragma once
// Stopping a lab test from outside: a RunOptions::progress callback throws RunCancelled (the
// worker's lease is gone, its campaign cancelled, or the job is over its wall-time limit), and
// the run unwinds from the next progress report. So that a callback is heard within a fraction
// of a second even in phases that report no progress of their own, the step loop of every test
// (run_checked) calls poll_progress() every few dozen steps.
#include <stdexcept>
#include <string>

namespace demcal::lab {

/// A run stopped on request; not a failure of the simulation.
class RunCancelled : public std::runtime_error {
 public:
  explicit RunCancelled(const std::string& why) : std::runtime_error(why) {}
};

/// Calls the progress callback of the lab test running on this thread (run_lab_test) with the
/// fraction it last reported; does nothing outside a run or without a callback.
void poll_progress();

}  // namespace demcal::lab
