#pragma once
// The simulation box: bounds, and which axes are periodic (minimum-image convention).
#include <array>
#include <cmath>

#include "core/common/vec3.hpp"

namespace demcal {

struct Domain {
  Vec3 lo{-1e30, -1e30, -1e30};
  Vec3 hi{1e30, 1e30, 1e30};
  std::array<bool, 3> periodic{false, false, false};

  bool any_periodic() const { return periodic[0] || periodic[1] || periodic[2]; }
  Vec3 length() const { return hi - lo; }

  /// Shortest vector from a to b under the periodic axes. Hot loops use MinimumImage below.
  Vec3 separation(const Vec3& a, const Vec3& b) const {
    Vec3 d = b - a;
    for (int k = 0; k < 3; ++k)
      if (periodic[k]) {
        const double len = hi[k] - lo[k];
        d[k] -= len * std::nearbyint(d[k] / len);
      }
    return d;
  }
  /// Maps a position into the box along the periodic axes.
  void wrap(Vec3& x) const {
    for (int k = 0; k < 3; ++k)
      if (periodic[k]) {
        const double len = hi[k] - lo[k];
        x[k] -= len * std::floor((x[k] - lo[k]) / len);
      }
  }
};

/// The minimum-image map of a domain with its box lengths, half lengths and inverses
/// precomputed, for the hot loops. Most separations are shorter than half the box and are
/// returned as they are after one compare; only the others are rounded (a library call where the
/// target has no rounding instruction), with the same result as rounding every one.
class MinimumImage {
 public:
  explicit MinimumImage(const Domain& d) {
    for (int k = 0; k < 3; ++k) {
      len_[k] = d.hi[k] - d.lo[k];
      half_[k] = d.periodic[k] ? 0.5 * len_[k] : 1e300;  // a closed axis is never rounded
      inv_len_[k] = d.periodic[k] ? 1.0 / len_[k] : 0.0;
    }
  }
  Vec3 operator()(Vec3 d) const {
    for (int k = 0; k < 3; ++k)
      if (std::abs(d[k]) > half_[k]) d[k] -= len_[k] * std::nearbyint(d[k] * inv_len_[k]);
    return d;
  }

 private:
  Vec3 len_, half_, inv_len_;
};

}  // namespace demcal
