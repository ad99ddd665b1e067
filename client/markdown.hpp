#pragma once
// Markdown tables of parameters (contact-law models, lab-test settings), printed from the tables
// that parse and validate specs; docs/contact-models.md and docs/lab-tests.md hold this output
// verbatim (tests/client/test_cli.cpp fails when they drift).
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "client/format.hpp"
#include "core/contact/contact_law.hpp"

namespace demcal::cli {

/// A bound or default as printed in the tables: six digits, "none" for an unset value.
inline std::string table_number(double v) {
  return std::isnan(v) ? "none" : fmt(v, 6);
}

/// One row per parameter: name, unit, valid range, default, meaning; `first_column` heads the
/// names.
inline void print_param_table(std::ostream& out, const std::vector<contact::ParamDoc>& params,
                              const std::string& first_column) {
  out << "| " << first_column << " | unit | valid range | default | meaning |\n"
      << "|---|---|---|---|---|\n";
  for (const auto& p : params)
    out << "| `" << p.name << "` | " << p.unit << " | [" << table_number(p.lo) << ", "
        << table_number(p.hi) << "] | " << table_number(p.fallback) << " | " << p.doc << " |\n";
}

}  // namespace demcal::cli
