#pragma once
// shear_cell (seed 000 §2.7.4): the FT4 standard shear test with a vaned shear head (a mesh).
#include <array>

#include "core/lab/lab_run.hpp"
#include "core/model/shear_cell_settings.hpp"

namespace demcal::lab {

/// The flow function reported for a locus without cohesion (sigma_c = 0, ffc unbounded) and the
/// largest reported: free flowing is ffc > 10 (Jenike's classes, Schulze 2008 §3.3), a metric
/// must stay finite.
inline constexpr double kFfcCap = 100.0;

/// Mohr-circle evaluation of a linear yield locus tau = slope sigma + intercept with the
/// pre-shear point (sigma_pre, tau_pre) (Schulze 2008; seed 000 §2.7.4, Fig. 12 and 23).
struct MohrResult {
  bool consistent = false;  ///< false: no circle through the pre-shear point touches the locus
  double sigma_c = 0.0;     ///< unconfined yield strength; 0 for an intercept <= 0
  double sigma_1 = 0.0;     ///< major consolidation stress
  double ffc = 0.0;         ///< sigma_1 / sigma_c, at most kFfcCap (kFfcCap when sigma_c = 0)
  double phi_e = 0.0;       ///< effective angle of internal friction (deg)
  /// The consolidation circle (centre, radius), touching the locus; 0, 0 when not consistent.
  double centre_1 = 0.0, radius_1 = 0.0;
};
MohrResult mohr_evaluation(double slope, double intercept, double sigma_pre, double tau_pre);

}  // namespace demcal::lab
