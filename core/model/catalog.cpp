#include "core/model/catalog.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/error.hpp"
#include "core/model/lab_tests.hpp"
#include "core/model/material.hpp"

namespace demcal::lab {

namespace {

/// The catalogue entry of test type T with what the registry reads from its types: the
/// cross-setting rules of its settings and the preparations it runs.
template <class T>
LabTestInfo registered_info() {
  using S = typename T::SettingsType;
  LabTestInfo info = T::info();
  if constexpr (requires { S::rules(); })
    for (const auto& r : S::rules()) info.rules.push_back({r.field, r.requirement, r.breaking});
  info.preparations = T::preparations();
  return info;
}

/// The particles (bodies) a run of T asks for: its `particles` setting, or what a test that
/// sizes its bed from the material says (T::admit, which also checks that bed: the drum's from
/// its geometry and fill, the packing's sampling volume).
template <class T>
std::size_t sized_bed(const MaterialModel& material, const typename T::SettingsType& s,
                      const std::string& where) {
  if constexpr (requires { T::admit(material, s, where); })
    return T::admit(material, s, where);
  else
    return static_cast<std::size_t>(std::llround(s.particles));
}

bool runs_preparation(const LabTestInfo& info, PreparationMethod method) {
  return std::ranges::find(info.preparations, method) != info.preparations.end();
}

/// The material's bed preparation against what test T runs and what the method can grow.
void check_preparation(const LabTestInfo& info, const MaterialModel& material,
                       const std::string& where) {
  const PreparationMethod method = material.preparation.method;
  if (!runs_preparation(info, method)) {
    std::string names;
    for (auto m : info.preparations)
      names += (names.empty() ? "" : ", ") + preparation_method_name(m);
    throw InputError(where + ".preparation.method",
                     "the " + info.name + " test cannot build its bed by '" +
                         preparation_method_name(method) + "' (it runs: " + names + ")");
  }
  if (method == PreparationMethod::kGrowth && material.clump_template())
    throw InputError(where + ".preparation.method",
                     "growth grows spheres only (a clump's members would have to move apart as "
                     "they grow); use pour, clusters, random_motion or terminal_velocity");
}

template <class T>
std::size_t admit_as(const LabTestInfo& info, const MaterialModel& material,
                     const Settings& settings, const FieldPaths& where) {
  validate_settings(info, settings, where.settings);
  const auto typed = read_settings<typename T::SettingsType>(settings, where.settings);
  check_preparation(info, material, where.material);
  return sized_bed<T>(material, typed, where.settings);
}

using Admission = std::size_t (*)(const LabTestInfo&, const MaterialModel&, const Settings&,
                                  const FieldPaths&);

}  // namespace

const std::vector<LabTestInfo>& lab_catalog() {
  static const std::vector<LabTestInfo> tests = std::apply(
      [](auto... test) { return std::vector<LabTestInfo>{registered_info<decltype(test)>()...}; },
      LabTests{});
  return tests;
}

const LabTestInfo& find_lab_info(const std::string& name) {
  std::string known;
  for (const auto& t : lab_catalog()) {
    if (t.name == name) return t;
    known += (known.empty() ? "" : ", ") + t.name;
  }
  throw InputError("test", "unknown lab test '" + name + "' (known: " + known + ")");
}

void validate_settings(const LabTestInfo& info, const Settings& settings,
                       const std::string& where) {
  for (const auto& [key, value] : settings) {
    const contact::ParamDoc* doc = nullptr;
    for (const auto& d : info.settings)
      if (d.name == key) doc = &d;
    if (!doc) throw InputError(where + "." + key, "not a setting of lab test '" + info.name + "'");
    if (!(value >= doc->lo && value <= doc->hi))
      throw InputError(where + "." + key,
                       "value " + std::to_string(value) + " outside the valid range [" +
                           std::to_string(doc->lo) + ", " + std::to_string(doc->hi) + "]");
  }
}

std::size_t admit_lab_test(const std::string& test, const MaterialModel& material,
                           const Settings& settings, const FieldPaths& where) {
  static const std::map<std::string, Admission> admissions = std::apply(
      [](auto... t) {
        return std::map<std::string, Admission>{
            {decltype(t)::info().name, &admit_as<decltype(t)>}...};
      },
      LabTests{});
  const LabTestInfo& info = find_lab_info(test);  // an unknown name: the known ones listed
  return admissions.at(test)(info, material, settings, where);
}

bool reports_metric(const LabTestInfo& info, const std::string& metric) {
  return std::ranges::any_of(info.metrics,
                             [&metric](const MetricInfo& m) { return m.name == metric; }) ||
         std::ranges::find(info.also_reported, metric) != info.also_reported.end();
}

double setting_value(const LabTestInfo& info, const Settings& settings, const std::string& name) {
  if (const auto it = settings.find(name); it != settings.end()) return it->second;
  for (const auto& doc : info.settings)
    if (doc.name == name) return doc.fallback;
  throw InputError("settings." + name, "not a setting of the " + info.name + " test");
}

bool accepts_preparation(const std::string& test, PreparationMethod method) {
  return runs_preparation(find_lab_info(test), method);
}

}  // namespace demcal::lab
