#pragma once
// What a job is for, as jobs.kind stores it and JobResult.kind reports it: written by the
// coordinator, read by the coordinator, the report and the exports' readers.
#include <string>
#include <string_view>

namespace demcal::job_kind {

/// A row of the campaign's design (std_order = the row).
inline constexpr std::string_view kDesign = "design";
/// A design row of a multi-fidelity campaign, run at the high fidelity level as well.
inline constexpr std::string_view kHighDesign = "design:high";
/// A job of a calibration round (std_order = the round).
inline constexpr std::string_view kVerify = "verify";

inline constexpr std::string_view kStagePrefix = "stage:";
inline constexpr std::string_view kDiagnosisPrefix = "diagnose:";

/// "stage:<n>": a design row laid over the box of the calibration's stage n.
inline std::string stage(int n) {
  return std::string(kStagePrefix) + std::to_string(n);
}
inline bool is_stage(std::string_view kind) {
  return kind.starts_with(kStagePrefix);
}

/// "diagnose:<group>": a run the diagnosis asked for (std_order = the group's row).
inline std::string diagnosis(std::string_view group) {
  return std::string(kDiagnosisPrefix) + std::string(group);
}
inline bool is_diagnosis(std::string_view kind) {
  return kind.starts_with(kDiagnosisPrefix);
}
/// The group of a diagnosis job's kind.
inline std::string diagnosis_group(std::string_view kind) {
  return std::string(kind.substr(kDiagnosisPrefix.size()));
}

}  // namespace demcal::job_kind
