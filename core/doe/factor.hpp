#pragma once
// A factor's box in natural units and its map to coded units: -1 at `low`, +1 at `high`.
// Log-scaled factors (Hamaker constant, Young's modulus over decades) are coded linearly in
// log10, so the design centre is the geometric mean of the bounds.
#include <string>

namespace demcal::doe {

enum class Scale { kLinear, kLog };

struct Factor {
  std::string name;
  double low = -1.0;
  double high = 1.0;
  Scale scale = Scale::kLinear;

  /// Throws InputError unless low < high (and low > 0 on a log scale).
  void validate() const;
  double to_coded(double natural) const;
  double to_natural(double coded) const;
  /// The variable the seed's equations are linear in: the natural value, or its log10 on a
  /// log scale (seed 000 §2.5.2 writes b_i per unit of xi_i).
  double xi(double natural) const;
  /// xi(high) - xi(low).
  double xi_range() const { return xi(high) - xi(low); }
  /// The design centre in natural units (arithmetic or geometric mean of the bounds).
  double centre() const { return to_natural(0.0); }
};

}  // namespace demcal::doe
