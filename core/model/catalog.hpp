#pragma once
// The catalogue of virtual lab tests: names, metrics (DESIGN.md names and units), settings tables.
// Metadata only, without the physics, so the coordinator can validate campaigns (test names,
// metric names, settings) without linking the DEM engine. The tests are listed in lab_tests.hpp;
// their runners are in core/lab.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/common/error.hpp"
#include "core/contact/contact_law.hpp"
#include "core/contact/param_table.hpp"
#include "core/model/preparation.hpp"

namespace demcal::lab {

struct MaterialModel;  // material.hpp
struct LabOutput;      // core/lab/lab_run.hpp: what a runner returns
struct RunOptions;     // core/lab/lab_run.hpp: how it runs

struct MetricInfo {
  std::string name, unit, description;
};

using Settings = std::map<std::string, double>;

/// A rule across a test's settings (each setting's own range is in its table), checked by the
/// settings' finalize() wherever they are read: at Submit, in `demcal lab run` and on the worker.
/// `breaking` is a settings map inside every range that breaks the rule, so that every rule has
/// a test refusing it.
template <class S>
struct SettingsRule {
  const char* field;        ///< the setting an error names
  const char* requirement;  ///< e.g. "must be < max_stress"
  bool (*holds)(const S&);
  Settings breaking;
};

/// A settings rule as the catalogue lists it.
struct RuleDoc {
  std::string field, requirement;
  Settings breaking;
};

/// How a test consolidates its bed before it measures: the setting of the stress it is consolidated
/// at and the settings of the consolidation's cycles that scale with it (a bed conditioned at a
/// k times lower stress has every one of them k times lower), and the metric that measures the
/// solid fraction the consolidation leaves, where the test reports one.
struct Consolidation {
  std::string stress;
  std::vector<std::string> scaled;
  std::string density_metric = {};
};

struct LabTestInfo {
  std::string name;
  std::string description;
  std::string source;  ///< seed section
  std::vector<MetricInfo> metrics;
  std::vector<contact::ParamDoc> settings;  ///< name, unit, range, default, meaning
  /// What the runner reports beside its metrics, as context and never as a response (a drum's
  /// particle count, its centrifuging at every speed): a result may carry these names too.
  std::vector<std::string> also_reported = {};
  /// The test whose conditioned bed a run of this one starts from, taken from the stage cache
  /// when a run of it with the same material, settings and seed kept it (core/lab/stage_cache.hpp):
  /// the coordinator leases this test's job of a design row after that test's job of the row.
  std::string starts_from = {};
  /// How it consolidates its bed; absent where it does not.
  std::optional<Consolidation> consolidation = {};
  /// Filled in by the registry from the test's type (lab_catalog()):
  std::vector<RuleDoc> rules = {};                   ///< cross-setting rules
  std::vector<PreparationMethod> preparations = {};  ///< the bed preparations it can run
};

/// Whether a run of the test `info` describes reports a metric of that name: one of its metrics
/// or of what it also reports (a result naming anything else is refused by the coordinator).
bool reports_metric(const LabTestInfo& info, const std::string& metric);

/// A setting's value in `settings`, or its default where they do not set it; InputError for a name
/// the test has no setting of.
double setting_value(const LabTestInfo& info, const Settings& settings, const std::string& name);

/// All lab tests, in a fixed order.
const std::vector<LabTestInfo>& lab_catalog();
/// The test of that name; InputError listing the known names otherwise.
const LabTestInfo& find_lab_info(const std::string& name);
/// Checks every setting name and value against the test's table; errors name `where`.<setting>.
void validate_settings(const LabTestInfo& info, const Settings& settings, const std::string& where);

/// Where the fields a lab test is admitted on live in the caller's input.
struct FieldPaths {
  std::string settings = "settings";  ///< e.g. "spec.tests[2].settings"
  std::string material = "material";  ///< e.g. "spec.material"
};

/// Every rule a lab test's runner would refuse its input with, checked before anything runs:
/// the settings' names, ranges and cross-setting rules, the material's bed preparation against
/// the ones the test can run, and the geometry a test sizes from the material (the rotating
/// drum's bed). Submit, `demcal lab run` and the worker call it alike. Returns the number of
/// particles (bodies) the run asks for; InputError naming the field otherwise.
std::size_t admit_lab_test(const std::string& test, const MaterialModel& material,
                           const Settings& settings, const FieldPaths& where = {});

/// Whether lab test `test` can build its beds by `method`.
bool accepts_preparation(const std::string& test, PreparationMethod method);

/// Checks a settings struct's cross-setting rules (S::rules()); errors name `where`.<field>.
template <class S>
void check_rules(const S& s, const std::string& where) {
  for (const auto& rule : S::rules())
    if (!rule.holds(s)) throw InputError(where + "." + rule.field, rule.requirement);
}

/// Reads a settings struct S (with S::table()) from a map, checking names and ranges.
template <class S>
S read_settings(const Settings& values, const std::string& where) {
  return contact::params_from_map<S>(values, where);
}
/// The documentation rows of a settings struct, for LabTestInfo::settings.
template <class S>
std::vector<contact::ParamDoc> settings_docs() {
  std::vector<contact::ParamDoc> out;
  for (const auto& p : S::table())
    out.push_back(
        {std::string(p.name), std::string(p.unit), std::string(p.doc), p.lo, p.hi, p.fallback});
  return out;
}

}  // namespace demcal::lab
