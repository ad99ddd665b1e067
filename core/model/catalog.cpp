#include "core/model/catalog.hpp"

#include "core/common/error.hpp"
#include "core/model/lab_tests.hpp"
#include "core/model/material.hpp"

namespace demcal::lab {

const std::vector<LabTestInfo>& lab_catalog() {
  static const std::vector<LabTestInfo> tests = std::apply(
      [](auto... test) { return std::vector<LabTestInfo>{decltype(test)::info()...}; }, LabTests{});
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

void check_size(const std::string& test, const MaterialModel& material, const Settings& settings,
                const std::string& where) {
  if (test != "rotating_drum") return;  // the other tests are sized by their particle count
  drum_bed(read_settings<RotatingDrumSettings>(settings, where), material.simulated_sizes(), where);
}

}  // namespace demcal::lab
