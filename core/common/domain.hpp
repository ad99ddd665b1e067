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

  /// Shortest vector from a to b under the periodic axes.
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

}  // namespace demcal
