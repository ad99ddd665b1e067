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

/// The minimum-image map of a domain with its box lengths and their inverses precomputed, for
/// the pair loop (a multiply instead of a divide per axis and pair).
class MinimumImage {
 public:
  explicit MinimumImage(const Domain& d) : periodic_(d.periodic) {
    for (int k = 0; k < 3; ++k) {
      len_[k] = d.hi[k] - d.lo[k];
      inv_len_[k] = periodic_[k] ? 1.0 / len_[k] : 0.0;
    }
  }
  Vec3 operator()(Vec3 d) const {
    for (int k = 0; k < 3; ++k)
      if (periodic_[k]) d[k] -= len_[k] * std::nearbyint(d[k] * inv_len_[k]);
    return d;
  }

 private:
  std::array<bool, 3> periodic_;
  Vec3 len_, inv_len_;
};

}  // namespace demcal
