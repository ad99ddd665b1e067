#pragma once
// The catalogue of virtual lab tests: names, metrics (DESIGN.md names and units), settings tables.
// Metadata only, without the physics, so the coordinator can validate campaigns (test names,
// metric names, settings) without linking the DEM engine. The tests are listed in lab_tests.hpp;
// their runners are in core/lab.
#include <map>
#include <string>
#include <vector>

#include "core/contact/contact_law.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::lab {

struct MaterialModel;  // material.hpp
struct LabOutput;      // core/lab/lab_test.hpp: what a runner returns
struct RunOptions;     // core/lab/lab_test.hpp: how it runs

struct MetricInfo {
  std::string name, unit, description;
};

using Settings = std::map<std::string, double>;

struct LabTestInfo {
  std::string name;
  std::string description;
  std::string source;  ///< seed section
  std::vector<MetricInfo> metrics;
  std::vector<contact::ParamDoc> settings;  ///< name, unit, range, default, meaning
  /// What the runner reports beside its metrics, as context and never as a response (a drum's
  /// particle count, its centrifuging at every speed): a result may carry these names too.
  std::vector<std::string> also_reported = {};
};

/// All lab tests, in a fixed order.
const std::vector<LabTestInfo>& lab_catalog();
/// The test of that name; InputError listing the known names otherwise.
const LabTestInfo& find_lab_info(const std::string& name);
/// Checks every setting name and value against the test's table; errors name `where`.<setting>.
void validate_settings(const LabTestInfo& info, const Settings& settings, const std::string& where);

/// Checks what a test's settings ask of the machine for this material before anything runs (the
/// rotating drum's particle count against its max_particles); InputError names `where`.<setting>.
void check_size(const std::string& test, const MaterialModel& material, const Settings& settings,
                const std::string& where);

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
