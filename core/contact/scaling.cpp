#include "core/contact/scaling.hpp"

#include <cmath>
#include <stdexcept>

namespace demcal::contact {
namespace {

double factor_for_unit(std::string_view unit, const ScaleFactors& f) {
  if (unit == "m") return f.length;
  if (unit == "N/m") return f.stiffness;
  if (unit == "Pa") return f.modulus;
  if (unit == "J") return f.hamaker;
  return 1.0;  // dimensionless ratios, coefficients and flags do not scale
}

template <class Variant>
Variant scale_slot(const Variant& slot, const ScaleFactors& f) {
  return std::visit(
      [&](auto m) -> Variant {
        for (const auto& info : decltype(m)::table()) {
          double& v = m.*info.field;
          if (is_set(v)) v *= factor_for_unit(info.unit, f);
        }
        m.finalize("scaled law");
        return m;
      },
      slot);
}

}  // namespace

ScaleFactors scale_factors(ScalingLaw law, double factor) {
  if (!(factor > 0.0)) throw InputError("scaling.factor", "must be > 0");
  ScaleFactors s;
  switch (law) {
    case ScalingLaw::kNone:
      break;
    case ScalingLaw::kKottlan2018:
      s.length = factor;
      s.density = 1.0 / (factor * factor * factor);
      s.modulus = 1.0 / (factor * factor);
      s.stiffness = 1.0 / factor;
      s.stress = 1.0 / (factor * factor);
      s.hamaker = factor;
      s.time = std::sqrt(factor);
      break;
    case ScalingLaw::kTiscar2019: {
      const double third = std::cbrt(factor);
      s.length = third;
      s.density = 1.0 / factor;
      s.stiffness = 1.0 / third;
      s.modulus = 1.0 / (third * third);
      s.stress = 1.0 / (third * third);
      s.hamaker = third;
      s.time = std::sqrt(third);
      break;
    }
  }
  return s;
}

ScalingLaw scaling_law_from_name(const std::string& name, const std::string& where) {
  if (name == "none") return ScalingLaw::kNone;
  if (name == "kottlan2018") return ScalingLaw::kKottlan2018;
  if (name == "tiscar2019") return ScalingLaw::kTiscar2019;
  throw InputError(where,
                   "unknown scaling law '" + name + "' (known: none, kottlan2018, tiscar2019)");
}

std::string scaling_law_name(ScalingLaw law) {
  switch (law) {
    case ScalingLaw::kNone:
      return "none";
    case ScalingLaw::kKottlan2018:
      return "kottlan2018";
    case ScalingLaw::kTiscar2019:
      return "tiscar2019";
  }
  throw std::logic_error("scaling law without a name");
}

ContactLaw scale(const ContactLaw& law, const ScaleFactors& f) {
  return {scale_slot(law.normal, f), scale_slot(law.cohesion, f), scale_slot(law.tangential, f),
          scale_slot(law.rolling, f)};
}

}  // namespace demcal::contact
