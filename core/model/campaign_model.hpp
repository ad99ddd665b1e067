#pragma once
// The material side of a campaign, checked in one call: each test instance admitted with its
// settings and material, the fixed values, the factors and their ties, the fidelity axis, and
// every planned run admitted as a worker would admit it. What the coordinator's plan needs from
// the catalogue comes back with it: each instance's metrics and its settings at both fidelity
// levels. And the diagnosis's model switches on a material model.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/model/catalog.hpp"
#include "core/model/material.hpp"

namespace demcal::lab {

/// One test instance of a campaign.
struct CampaignInstance {
  std::string name;  ///< what its responses start with ("<name>.<metric>")
  std::string test;  ///< the lab test
  Settings settings;
  MaterialModel material;  ///< the campaign's, with the instance's own wall law and preparation
  std::uint64_t seed = 1;  ///< the simulation seed of its first row
  std::string where;       ///< its field, e.g. "spec.tests[2]"
};

/// A factor: a parameter path between two bounds, and the paths tied to its value.
struct CampaignFactor {
  std::string path;
  double low = 0.0, high = 0.0;
  bool log = false;
  std::vector<std::string> tied;
  std::string where;  ///< its field, e.g. "spec.factors[1]"
};

/// The fidelity axis: a test setting ("settings.<name>") or a material parameter at two levels.
struct CampaignFidelity {
  std::string path;
  double low = 0.0, high = 0.0;
};

/// A planned design row: the parameters every instance runs it with (fixed values, factors, ties
/// and a fidelity parameter's level), at the low or the high fidelity level.
struct CampaignRun {
  int row = 0;  ///< 1-based standard order, for error messages
  bool high = false;
  std::map<std::string, double> parameters;
};

struct CampaignModel {
  MaterialModel material;  ///< the campaign's
  std::vector<ParameterValue> fixed;
  std::vector<CampaignInstance> instances;
  std::vector<CampaignFactor> factors;
  std::optional<CampaignFidelity> fidelity;
  std::vector<CampaignRun> runs;
};

/// What the catalogue says of one instance: its metrics and its settings at each fidelity level
/// (a setting fidelity axis's level in place where the test has that setting).
struct ModelledInstance {
  std::vector<std::string> metrics;
  Settings low, high;
  /// The instance whose job of a row this one's waits for: the first of the test it starts from
  /// (LabTestInfo::starts_from) with its seed; empty when none.
  std::string waits_for;
};

/// The prefix of a fidelity axis that is a test setting.
inline constexpr std::string_view kSettingsPrefix = "settings.";

/// A test's settings at a fidelity level: the level in place when the axis is a setting the test
/// has, else as they are.
Settings at_fidelity_level(const std::string& test, Settings settings,
                           const CampaignFidelity& fidelity, bool high);

/// Checks the campaign's material side; InputError naming the field:
/// - each instance's test in the catalogue, admitted (admit_lab_test) with its settings;
/// - each fixed value a parameter of the material and of every instance, inside its range;
/// - each factor a parameter of the material and of every instance, not fixed, not twice, its
///   bounds finite, ordered, inside the valid range and > 0 on a log scale; each tied path the
///   same and set by nothing else;
/// - the fidelity axis: a setting some instance has, admitted at both levels, or a parameter no
///   factor, tie or fixed value sets, valid at both levels;
/// - every run of every instance admitted at its parameters and level.
std::vector<ModelledInstance> model_campaign(const CampaignModel& campaign);

/// The fields an instance's admission names: its settings, and for the material the campaign's
/// (`spec.material`), or the instance's own (`where`) when its bed preparation is its own, so that
/// a preparation its test cannot build is named where it was written.
FieldPaths instance_fields(const std::string& where, const MaterialModel& instance,
                           const MaterialModel& campaign);

/// Admits one run of a test: `material` with `parameters` set, at `settings`; InputError naming
/// the field, with the design row ("design run 3: ...").
void admit_run(const std::string& test, const MaterialModel& material,
               const std::map<std::string, double>& parameters, const Settings& settings,
               const FieldPaths& paths, int row);

/// The material with the diagnosis's model switches applied ({what: value}):
///   shape: <kind>                 the particle shape, at its default parameters;
///   particle_law.rolling: <model> the particles' rolling model, at mu_r = 0 (the walls keep
///                                 their law: rolling resistance between particles only);
///   preparation: <method>         the bed preparation at its default parameters;
///   sizes: lognormal              one size becomes the median of a log-normal distribution of
///                                 width particles::kNarrowestLogNormal (a distribution stays as it
///                                 is).
/// InputError on an unknown switch.
MaterialModel with_switches(MaterialModel material,
                            const std::map<std::string, std::string>& switches);

/// The switches a test instance takes (a subset of `switches`): a preparation switch only where
/// the instance's test builds its beds by that method and the instance has no preparation of its
/// own (`instance`'s equals the campaign material's); the others always. An instance that does
/// not take a switch runs as it would without it.
std::map<std::string, std::string> instance_switches(
    const std::string& test, const MaterialModel& instance, const MaterialModel& campaign,
    const std::map<std::string, std::string>& switches);

/// `parameters` without those of the switches an instance did not take (`switches` minus
/// `taken`): a switch's parameters are the paths under its name ("preparation.agitation_time").
std::map<std::string, double> taken_parameters(std::map<std::string, double> parameters,
                                               const std::map<std::string, std::string>& switches,
                                               const std::map<std::string, std::string>& taken);

}  // namespace demcal::lab
