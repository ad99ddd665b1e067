#pragma once
// The version of the lab tests' protocols. A finished run is known by its run key, a hash of
// everything that determines its result (the material, the test and its settings, the seed) and
// of this number: a journal or a store hands a run's result to a later job with the same key
// instead of simulating it again (docs/journal.md). Raise it whenever a change to a lab test's
// protocol (its phases, targets, metrics or their definitions) changes its results, so that no
// result of the old protocol is taken for a run of the new one.
namespace demcal::lab {

inline constexpr int kProtocolVersion = 2;

}  // namespace demcal::lab
