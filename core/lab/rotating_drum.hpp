#pragma once
// rotating_drum (seed 001 §3.2.2-3.2.3): dynamic angle of repose at `rpm` (4 in the seed) and the
// area method (occupied cross-sectional area, eq. 20) at 4, 40, 80, 105 and 116 rpm, in a drum
// given in real units whose particle count follows from its size, its fill and the sizes.
#include <array>
#include <utility>
#include <vector>

#include "core/lab/lab_run.hpp"
#include "core/model/rotating_drum_settings.hpp"
#include "core/particles/size_distribution.hpp"

namespace demcal::lab {
/// The drum cross-section as an image (seed 001 §3.2.2: ImageJ on photographs): particles of
/// `world` projected along the drum axis z onto a raster of pixel `pixel` over [-R, R]^2.
struct DrumImage {
  int n = 0;  ///< pixels per side
  double pixel = 0.0, radius = 0.0;
  std::vector<char> black;
  bool at(int i, int j) const { return black[static_cast<std::size_t>(j) * n + i] != 0; }
  /// Occupied cross-sectional area in % of the drum's (seed 001 eq. 20).
  double occupied_percent() const;
  /// The free surface (x, y) from wall to wall: per column the top black pixel with black below
  /// it (a lone particle in flight is not the surface); gravity along -y.
  std::vector<std::pair<double, double>> surface() const;
  /// Angle (deg) of a straight line fitted to the free surface over the middle half of its
  /// horizontal extent.
  double surface_angle() const;
};
DrumImage project_drum(const std::vector<Vec3>& x, const std::vector<double>& radius,
                       double drum_radius, double pixel);

}  // namespace demcal::lab
