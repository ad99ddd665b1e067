#pragma once
// No cohesion slot: the pair attracts only through its normal law (e.g. Luding's kc branch).
#include <array>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::cohesion {

struct None {
  static constexpr const char* kName = "none";
  static std::array<ParamInfo<None>, 0> table() { return {}; }
  void finalize(const std::string&) {}
  double range() const { return 0.0; }
  double force(const PairInput&) const { return 0.0; }
  double contact_force(double /*r_eff*/) const { return 0.0; }
  double approach_work(double /*r_eff*/) const { return 0.0; }
};

}  // namespace demcal::contact::cohesion
