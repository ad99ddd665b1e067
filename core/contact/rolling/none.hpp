#pragma once
// No rolling resistance.
#include <array>

#include "core/contact/pair.hpp"
#include "core/contact/param_table.hpp"

namespace demcal::contact::rolling {

struct None {
  static constexpr const char* kName = "none";
  static constexpr int kHistory = 0;
  static std::array<ParamInfo<None>, 0> table() { return {}; }
  void finalize(const std::string&) {}
  Vec3 torque(const PairInput&, const NormalResult&, double, double*) const { return {}; }
};

}  // namespace demcal::contact::rolling
