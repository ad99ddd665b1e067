#pragma once
// The versions of the lab tests' protocols. A finished run is known by its run key, a hash of
// everything that determines its result (the material, the test and its settings, the seed) and
// of its test's protocol version: a journal or a store hands a run's result to a later job with
// the same key instead of simulating it again (docs/journal.md). Raise a test's version whenever a
// change to its protocol (its phases, targets, metrics or their definitions) changes its results,
// so that no result of the old protocol is taken for a run of the new one, while the runs of the
// other tests stay valid.
#include <array>
#include <string_view>
#include <utility>

namespace demcal::lab {

/// The version of every test whose protocol has not changed on its own since this number was
/// raised for all of them.
inline constexpr int kProtocolVersion = 2;

/// The tests with a version of their own:
///   shear_cell 3: the head is lowered into the settled bed instead of placed in it at once.
///   shear_cell 4: the consolidation goes on until the floor holds sigma_pre, and the pre-shear
///     until the flow is steady at sigma_pre (at least pre_shear_travel).
///   tensile 3: the unload with the adhesive piston bounds the controller's step by the piston's
///     contact stiffness.
///   tensile 4: the die keeps the compression's law through the unload and becomes frictionless
///     and non-cohesive for the pull; a peak in the pull's last tenth flags the strength.
inline constexpr std::array<std::pair<std::string_view, int>, 2> kOwnProtocolVersions = {
    {{"shear_cell", 4}, {"tensile", 4}}};

/// The protocol version of lab test `test`.
constexpr int protocol_version(std::string_view test) {
  for (const auto& [name, version] : kOwnProtocolVersions)
    if (name == test) return version;
  return kProtocolVersion;
}

}  // namespace demcal::lab
